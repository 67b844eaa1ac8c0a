/* The deterministic example flight of gnss_attitude::receiver::example, from C.
 *
 * Flies epochs 0..600 (0.6 s: cold start, then the fine filter) through the C ABI exactly as
 * ExampleFlight::fly does in Rust, prints the attitude, the events, the NMEA sentences and the
 * binary record, and exits 0 only when the attitude is the one-stage filter's and within
 * 0.2 degrees of the truth (and the error paths answer as documented).
 *
 * Host:  cc -O2 -I ../../ffi/include scenario.c libgnss_attitude_ffi.a -lm -lpthread -ldl
 * Target (Cortex-M4F under QEMU, semihosting): see qemu/ and .ci/ffi_and_board.sh.
 * With -DGA_MEASURE every receiver call is bracketed by the marker instructions that QEMU's
 * insnmark plugin counts, and a line "calls: ..." names the call of each region in order.
 * SPDX-License-Identifier: MIT OR Apache-2.0 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "gnss_attitude.h"

#define EPOCHS 600u
#define MAX_SATS 12u
#ifndef TOLERANCE_DEG
#define TOLERANCE_DEG 0.2f /* CI builds it once with a tiny tolerance: the run must then fail */
#endif

#ifdef GA_MEASURE
#define MAX_REGIONS 8192u
static char region_calls[MAX_REGIONS + 1];
static unsigned regions;
/* mov r8, r8 / mov r9, r9: QEMU's insnmark plugin counts the instructions in between */
#define MEASURE(tag, expr)                                                                  \
  ({                                                                                        \
    __asm__ volatile("mov r8, r8" ::: "memory");                                            \
    GaStatus measured_status_ = (expr);                                                     \
    __asm__ volatile("mov r9, r9" ::: "memory");                                            \
    if (regions < MAX_REGIONS) region_calls[regions++] = (tag);                             \
    measured_status_;                                                                       \
  })
#else
#define MEASURE(tag, expr) (expr)
#endif

/* Static storage: no allocator. Zero-initialized, as C statics are. */
static GaReceiver receiver;
static GaExampleFlight flight;
static GaReceiver never_initialized;

static int failures;

static void expect(int ok, const char *what) {
  if (!ok) {
    printf("FAIL: %s\n", what);
    failures++;
  }
}

static int check(GaStatus s, const char *call) {
  if (s != GA_STATUS_OK) {
    GaError e;
    ga_receiver_last_error(&receiver, &e);
    printf("FAIL: %s returned %d (%s), last error: status %d kind %u call %u epoch %llu\n",
           call, (int)s, ga_status_str(s), (int)e.status, e.kind, e.call,
           (unsigned long long)e.epoch);
    failures++;
    return 0;
  }
  return 1;
}

static const char *event_name(GaEventKind k) {
  switch (k) {
    case GA_EVENT_KIND_FIRST_FIX: return "first fix";
    case GA_EVENT_KIND_FIX_REFUSED: return "fix refused";
    case GA_EVENT_KIND_FINE_LOCKED: return "fine locked";
    case GA_EVENT_KIND_FINE_LOCK_LOST: return "fine lock lost";
    case GA_EVENT_KIND_REANCHORED: return "re-anchored";
    case GA_EVENT_KIND_SATELLITE_ACQUIRED: return "satellite acquired";
    case GA_EVENT_KIND_SATELLITE_LOST: return "satellite lost";
    case GA_EVENT_KIND_AMBIGUITY_FIXED: return "ambiguity fixed";
    case GA_EVENT_KIND_CYCLE_SLIP: return "cycle slip";
    case GA_EVENT_KIND_ANTENNA_BLOCKED: return "antenna blocked";
    case GA_EVENT_KIND_ANTENNA_RESTORED: return "antenna restored";
    case GA_EVENT_KIND_BIT_ANOMALY: return "bit anomaly";
    case GA_EVENT_KIND_GYRO_CALIBRATED: return "gyro calibrated";
    default: return "other";
  }
}

/* The error paths: an uninitialized object, a null pointer, a satellite without aiding. */
static void error_paths(void) {
  GaAttitude att;
  GaError e;
  expect(ga_receiver_attitude(&never_initialized, &att) == GA_STATUS_NOT_INITIALIZED,
         "an uninitialized receiver answers NOT_INITIALIZED");
  expect(ga_receiver_attitude(NULL, &att) == GA_STATUS_NULL_POINTER, "null storage");
  expect(ga_receiver_attitude(&receiver, NULL) == GA_STATUS_NULL_POINTER, "null output");
  GaObservation unknown;
  memset(&unknown, 0, sizeof unknown);
  unknown.prn = 1; /* not in the example's sky (PRNs 3 7 11 14 19 22 27 31) */
  unknown.noise_var = 1600.0f;
  unknown.cn0_dbhz = 45.0f;
  expect(ga_receiver_push_observation(&receiver, EPOCHS + 5u, &unknown) == GA_STATUS_NO_AIDING,
         "an observation without aiding answers NO_AIDING");
  expect(ga_receiver_last_error(&receiver, &e) == GA_STATUS_OK &&
             e.status == GA_STATUS_NO_AIDING && e.call == GA_CALL_PUSH_OBSERVATION &&
             e.epoch == EPOCHS + 5u,
         "the last error records the failed call and its epoch");
}

int main(void) {
  printf("gnss_attitude C example: GaReceiver %u B reserved (%u B used on this target), align %u\n",
         (unsigned)sizeof receiver, (unsigned)ga_receiver_used_size(), (unsigned)GA_STORAGE_ALIGN);
  if (ga_abi_version() != GA_ABI_VERSION) {
    printf("FAIL: library ABI %u, header ABI %u\n", (unsigned)ga_abi_version(), GA_ABI_VERSION);
    return 1;
  }
  GaConfig config;
  if (!check(ga_example_config(1, &config), "ga_example_config")) return 1;
  if (!check(MEASURE('I', ga_receiver_init(&receiver, &config)), "ga_receiver_init")) return 1;
  if (!check(ga_example_flight_init(&flight, 7), "ga_example_flight_init")) return 1;
  /* The stages out of the 1 ms path: a closing epoch only captures, ga_receiver_run_deferred
   * (here right after each epoch: the attitude is then the inline one, bit for bit) runs them. */
  check(ga_receiver_set_deferred_stages(&receiver, true), "ga_receiver_set_deferred_stages");
  bool ran = false;

  GaAiding aiding[MAX_SATS];
  GaObservation obs[MAX_SATS];
  float theta[3];
  size_t n = 0;
  for (uint64_t k = 0; k < EPOCHS && failures == 0; k++) {
    if (k % GA_EXAMPLE_EPOCHS_PER_AIDING == 0) {
      check(ga_example_aiding(&flight, k, aiding, MAX_SATS, &n), "ga_example_aiding");
      check(MEASURE('A', ga_receiver_set_aiding(&receiver, aiding, n)), "ga_receiver_set_aiding");
    }
    if (k > 0 && k % GA_EXAMPLE_EPOCHS_PER_GYRO == 0) {
      check(ga_example_gyro_increment(&flight, k / GA_EXAMPLE_EPOCHS_PER_GYRO - 1, theta),
            "ga_example_gyro_increment");
      check(MEASURE('G', ga_receiver_push_gyro_increment(&receiver, theta)),
            "ga_receiver_push_gyro_increment");
    }
    check(ga_example_observations(&flight, k, obs, MAX_SATS, &n), "ga_example_observations");
    for (size_t i = 0; i < n; i++) {
      check(MEASURE('O', ga_receiver_push_observation(&receiver, k, &obs[i])),
            "ga_receiver_push_observation");
    }
    check(MEASURE('D', ga_receiver_run_deferred(&receiver, &ran)), "ga_receiver_run_deferred");
  }
  check(MEASURE('C', ga_receiver_close_through(&receiver, EPOCHS - 1u)), "ga_receiver_close_through");
  check(MEASURE('D', ga_receiver_run_deferred(&receiver, &ran)), "ga_receiver_run_deferred");
  uint32_t overruns = 1;
  check(ga_receiver_deferred_overruns(&receiver, &overruns), "ga_receiver_deferred_overruns");
  expect(overruns == 0, "deferred work run after every epoch never overruns");

  GaAttitude att;
  check(MEASURE('T', ga_receiver_attitude(&receiver, &att)), "ga_receiver_attitude");
  GaEvent ev;
  unsigned events = 0;
  for (unsigned guard = 0; guard < 64u; guard++) {
    GaStatus s = MEASURE('E', ga_receiver_pop_event(&receiver, &ev));
    if (s != GA_STATUS_OK) {
      expect(s == GA_STATUS_EMPTY && ev.kind == GA_EVENT_KIND_NONE, "an empty queue answers EMPTY");
      break;
    }
    events++;
    printf("event: epoch %llu %s prn %u antenna %u\n", (unsigned long long)ev.epoch,
           event_name(ev.kind), ev.prn, ev.antenna);
  }

  float truth[4], error_rad = 1.0f;
  check(ga_example_truth(&flight, att.epoch, truth, att.q_rb, &error_rad), "ga_example_truth");
  float error_deg = error_rad * 57.2957795f;

  uint8_t line[GA_NMEA_MAX + 1];
  size_t len = 0;
  for (uint8_t sentence = 0; sentence < 2; sentence++) {
    if (check(MEASURE('N', ga_format_nmea(sentence, &att, NULL, line, GA_NMEA_MAX, &len)),
              "ga_format_nmea")) {
      line[len] = 0;
      printf("nmea: %s", (const char *)line);
    }
  }
  uint8_t record[GA_RECORD_LEN];
  if (check(MEASURE('R', ga_format_record(&att, record, sizeof record, &len)), "ga_format_record")) {
    printf("record (%u B):", (unsigned)len);
    for (size_t i = 0; i < len; i++) printf(" %02x", record[i]);
    printf("\n");
  }
  error_paths();

  /* %.9g: enough digits to carry an f32 exactly */
  printf("attitude: epoch %llu q %.9g %.9g %.9g %.9g source %u satellites %u fixed %u "
         "lock %u error %.4f deg events %u\n",
         (unsigned long long)att.epoch, (double)att.q_rb[0], (double)att.q_rb[1],
         (double)att.q_rb[2], (double)att.q_rb[3], att.source, att.health.satellites_used,
         att.health.satellites_fixed, att.health.fine_lock, (double)error_deg, events);
#ifdef GA_MEASURE
  region_calls[regions] = 0;
  printf("calls: %s\n", region_calls);
#endif
  int ok = failures == 0 && att.source == GA_SOURCE_FINE && error_deg < TOLERANCE_DEG &&
           events > 0;
  printf("c example: %s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
