# Checks the `navigation` object of a host-sim `track --json` run ($r) on a `synth --lnav`
# recording against its truth file ($t); prints the figures, `ok` decides.
# Usage: jq -e -c -n --slurpfile t truth.json --slurpfile r track.json -f .ci/check_navigation.jq
# Checks: every encoded ephemeris decoded with every field equal within 1e-12 relative (0 LSB),
# no parity failure, the first fix within 48 s with the truth's week and time of week (1 us),
# every fix within 10 m of the truth position, a finite PDOP below 10.
($t[0]) as $truth
| ($r[0].navigation) as $n
| ($n.ephemerides | map({key: (.prn | tostring), value: .}) | from_entries) as $D
| def dist($a; $b): ([range(3)] | map(($a[.] - $b[.]) | . * .) | add | sqrt);
  {
    ephemerides_sent: ($truth.ephemerides | length),
    ephemerides_decoded: ($n.ephemerides | length),
    ephemerides_equal: ([$truth.ephemerides[] | . as $e | $D[$e.prn | tostring] as $d
      | ($d != null) and ([$e | to_entries[] | ((.value - $d[.key]) | fabs) <= 1e-12 * ((.value | fabs) + 1e-300)] | all)] | all),
    parity_failures: $n.parity_failures,
    ttff_s: $n.ttff_s,
    fixes: $n.fixes,
    pdop: $n.pdop,
    tow_err_s: (if $n.tow_s then ($n.tow_s - ($truth.tow_s + $n.ttff_s)) | fabs else null end),
    week_ok: ($n.gps_week == $truth.gps_week),
    fix_err_m_max: ([$n.per_fix[] | dist(.position_ecef_m; $truth.position_ecef_m)] | max),
    mean_err_m: (if $n.position_ecef_m then dist($n.position_ecef_m; $truth.position_ecef_m) else null end)
  }
| . + {ok: (.ephemerides_equal and .ephemerides_decoded == .ephemerides_sent and .parity_failures == 0
    and .ttff_s != null and .ttff_s <= 48 and .fixes > 0 and .week_ok and .tow_err_s < 1e-6
    and .fix_err_m_max < 10 and .pdop < 10)}
