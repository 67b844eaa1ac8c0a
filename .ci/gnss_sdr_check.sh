#!/usr/bin/env bash
# An independent decoder proves the synthesizer (issue 17): Debian's GNSS-SDR decodes the LNAV
# message and fixes the position on a `host-sim synth --lnav` recording, and `host-sim track
# --json` (no --sky) runs on the same file; both rows are printed side by side.
#
# 1. installs gnss-sdr if missing (unattended, Debian 12: apt-get install --no-install-recommends)
#    and prints the install time; builds host-sim (release);
# 2. synthesizes an 80 s static recording, 8 satellites at 45 dB-Hz, cs8 (= GNSS-SDR's `ibyte`,
#    complex int8 interleaved, zero IF) at 4 MHz;
# 3. runs gnss-sdr with .ci/gnss_sdr.conf.in (GPS L1 C/A, 8 channels, RTKLIB single point,
#    broadcast ionosphere) and prints its run time;
# 4. .ci/gnss_sdr_compare.py checks its RINEX navigation file against the encoded ephemerides
#    (every field within 1 LNAV LSB) and its NMEA GGA fixes and KML track (within 15 m of the
#    truth), RTKLIB's receiver clock offset (the synthesizer's sample clock is GPS time: median
#    within 100 ns) and GNSS-SDR's C/N0 (within 2 dB of the synthesized), computes first-fix
#    time and median/worst horizontal and vertical error for both receivers. Exits non-zero if
#    GNSS-SDR decodes nothing or a check fails.
#
# Usage: bash .ci/gnss_sdr_check.sh          (from anywhere inside the repository)
# Environment: GNSS_SDR_FS (sample rate, Hz, default 4e6), GNSS_SDR_SECONDS (default 80),
#   GNSS_SDR_TIMEOUT (s, default 1200), GNSS_SDR_KEEP=1 keeps the recording (640 MB at 4 MHz).
# Output in target/gnss-sdr/ (result.json holds the figures docs/GNSS_SDR.md quotes).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
FS=${GNSS_SDR_FS:-4e6}
SECS=${GNSS_SDR_SECONDS:-80}
TIMEOUT=${GNSS_SDR_TIMEOUT:-1200}
WORK=$ROOT/target/gnss-sdr
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo -n"; fi

echo "=== gnss-sdr install ==="
install_s=0
missing=""
command -v gnss-sdr >/dev/null || missing="gnss-sdr"
command -v python3 >/dev/null || missing="$missing python3"
if [ -n "$missing" ]; then
  t0=$(date +%s)
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  # shellcheck disable=SC2086
  $SUDO apt-get install -y -q --no-install-recommends $missing
  install_s=$(( $(date +%s) - t0 ))
fi
echo "gnss-sdr install: ${install_s} s ($(gnss-sdr --version 2>&1 | grep -m1 -i version))"

echo "=== host-sim (release) and the recording ==="
cargo build --release -q -p host-sim
HS=$ROOT/target/release/host-sim
rm -rf "$WORK"
mkdir -p "$WORK/pvt" "$WORK/log"
CN0=45,45,45,45,45,45,45,45
$HS synth --out "$WORK" --name static --format cs8 --fs "$FS" --seconds "$SECS" --cn0 "$CN0" \
  --lnav --seed 5
FS_INT=$(python3 -c "print(int(round(float('$FS'))))")

echo "=== gnss-sdr ==="
sed -e "s|@FS@|$FS_INT|g" -e "s|@FILE@|$WORK/static.cs8|g" -e "s|@OUT@|$WORK/pvt|g" \
  .ci/gnss_sdr.conf.in > "$WORK/gnss-sdr.conf"
t0=$(date +%s.%N)
set +e
(cd "$WORK" && timeout "$TIMEOUT" gnss-sdr --config_file="$WORK/gnss-sdr.conf" --log_dir="$WORK/log" \
  > "$WORK/gnss-sdr.log" 2>&1)
status=$?
set -e
run_s=$(python3 -c "print(round($(date +%s.%N) - $t0, 1))")
echo "gnss-sdr: exit status $status after ${run_s} s (log: $WORK/gnss-sdr.log)"
grep -m3 -E "New GPS NAV message|Position at" "$WORK/gnss-sdr.log" || true
if [ "$status" != 0 ]; then tail -20 "$WORK/gnss-sdr.log"; echo "FAIL: gnss-sdr exited with $status"; exit 1; fi

echo "=== host-sim track --json (no --sky) on the same file ==="
t0=$(date +%s.%N)
$HS track --file "$WORK/static.cs8" --format cs8 --fs "$FS" --json --out "$WORK/track.out" \
  > "$WORK/track.json" 2>"$WORK/track.log"
track_s=$(python3 -c "print(round($(date +%s.%N) - $t0, 1))")

echo "=== comparison ==="
set +e
python3 .ci/gnss_sdr_compare.py --truth "$WORK/static.truth.json" --pvt-dir "$WORK/pvt" \
  --nmea "$WORK/pvt/gnss_sdr_pvt.nmea" --track "$WORK/track.json" --install-s "$install_s" \
  --run-s "$run_s" --track-s "$track_s" --glog "$WORK/log/gnss-sdr.INFO" --json-out "$WORK/result.json"
status=$?
set -e
[ "${GNSS_SDR_KEEP:-0}" = 1 ] || rm -f "$WORK/static.cs8"
exit "$status"
