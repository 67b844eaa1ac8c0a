# Checks a host-sim `acquire --json` or `track --json` object ($r) against the truth file of
# the synthesized recording ($t) and prints the figures; `jq -e` fails when `ok` is false.
# Usage: jq -e -n --slurpfile t truth.json --slurpfile r out.json --argjson loss 0 \
#          -f .ci/check_recording.jq
# `loss`: the quantization loss of the layout, dB (0.55 for 2-bit samples), taken off the
# synthesized C/N0 before the comparison. A noise-free recording (`noise: false` in the truth)
# has no C/N0 to compare: every satellite's C/N0 must then be finite (a number, not null).
# Every check: no PRN that is absent from the recording is reported or ever locked.
($t[0]) as $truth
| ($r[0]) as $out
| ($truth.satellites | map({key: (.prn | tostring), value: .}) | from_entries) as $T
| ($out.acquisition // $out) as $acq
| ($acq.detections) as $D
| def wrap: . - 1023 * ((. / 1023) | round);
  {
    prns_exact: (([$D[].prn] | sort) == ([$truth.satellites[].prn] | sort)),
    doppler_err_hz_max: ([$D[] | select($T[.prn | tostring]) | (.doppler_hz - $T[.prn | tostring].doppler_hz) | fabs] | max),
    code_err_chips_max: ([$D[] | select($T[.prn | tostring]) | (.code_phase_chips - $T[.prn | tostring].code_phase_chips) | wrap | fabs] | max),
    acquisition_search_s: $acq.search_s
  }
| (if $truth | has("noise") then $truth.noise else true end) as $noisy
| if $out.satellites then
    . + {
      all_held_to_end: ([$out.satellites[].held_to_end] | all),
      first_lock_s_max: ([$out.satellites[].first_lock_s] | max),
      absent_lock_s: ([$out.satellites[] | select($T[.prn | tostring] | not) | .lock_time_s] | add // 0),
      cn0_all_finite: ([$out.satellites[] | (.cn0_dbhz_mean | type) == "number"] | all),
      tracking_wall_s: $out.wall.tracking_s,
      tracked_s: $out.tracked_s
    }
    + (if $noisy then {
      cn0_err_db_max: ([$out.satellites[] | (.cn0_dbhz_thermal - ($T[.prn | tostring].cn0_dbhz - $loss)) | fabs] | max),
      cn0_measured_err_db_max: ([$out.satellites[] | (.cn0_dbhz_mean - ($T[.prn | tostring].cn0_dbhz - $loss)) | fabs] | max)
    } else {} end)
  else . end
| if $out.attitude then
    . + {
      attitude_windows_fixed: "\($out.attitude.fixed)/\($out.attitude.windows)",
      attitude_err_deg_max: ([$out.attitude.per_window[] | select(.ypr_deg) | [.ypr_deg, $truth.attitude_ypr_deg] | transpose[] | (.[0] - .[1]) | fabs] | max)
    }
  else . end
| . + {
    ok: (.prns_exact and .doppler_err_hz_max <= 250 and .code_err_chips_max <= 0.5
         and (if has("all_held_to_end") then .all_held_to_end and .absent_lock_s == 0 and .cn0_all_finite else true end)
         and (if has("cn0_err_db_max") then .cn0_err_db_max <= 1.5 else true end)
         and (if has("attitude_err_deg_max") then $out.attitude.fixed >= 1 and .attitude_err_deg_max <= 0.1 else true end))
  }
