#!/usr/bin/env python3
"""Checks GNSS-SDR's output on a `host-sim synth --lnav` recording against the synthesizer's truth
and prints it beside `host-sim track --json` on the same file (used by .ci/gnss_sdr_check.sh).

Checks (exit status 1 if one fails):
  * GNSS-SDR's RINEX navigation file holds an ephemeris for every PRN host-sim encoded, every
    compared field within one LNAV least significant bit (IS-GPS-200 scale factors, plus the
    RINEX print rounding) of the truth file's value;
  * GNSS-SDR's NMEA GGA fixes with PDOP <= 3 (from the GSA sentence of the epoch) exist and all
    lie within 15 m (3-D) of the truth position; its KML track exists and its median point lies
    within 15 m;
  * the receiver clock offset RTKLIB estimates (the synthesizer's sample clock is GPS time) has a
    median within 100 ns of zero, and GNSS-SDR's C/N0 (RINEX S1C, median per PRN) is within 2 dB
    of the synthesized one.
Prints the first-fix time (s after the first sample), median and worst horizontal/vertical error
for both receivers and writes the figures as one JSON object to --json-out.
"""

import argparse
import glob
import json
import math
import os
import re
import statistics
import sys

A_WGS84 = 6378137.0
F_WGS84 = 1.0 / 298.257223563
E2_WGS84 = F_WGS84 * (2.0 - F_WGS84)
PI = math.pi
LIMIT_M = 15.0
PDOP_GATE = 3.0
CLOCK_LIMIT_NS = 100.0
CN0_LIMIT_DB = 2.0

# One LNAV least significant bit of each compared field in RINEX units (IS-GPS-200 table 20-III
# and 20-I; semicircles converted to radians).
LSB = {
    "af0": 2.0**-31, "af1": 2.0**-43, "af2": 2.0**-55,
    "iode": 1.0, "crs": 2.0**-5, "delta_n": 2.0**-43 * PI, "m0": 2.0**-31 * PI,
    "cuc": 2.0**-29, "e": 2.0**-33, "cus": 2.0**-29, "sqrt_a": 2.0**-19,
    "toe_s": 16.0, "cic": 2.0**-29, "omega0": 2.0**-31 * PI, "cis": 2.0**-29,
    "i0": 2.0**-31 * PI, "crc": 2.0**-5, "omega": 2.0**-31 * PI, "omega_dot": 2.0**-43 * PI,
    "idot": 2.0**-43 * PI, "week": 1.0, "tgd": 2.0**-31, "iodc": 1.0,
}


def ecef_from_llh(lat_deg, lon_deg, h_m):
    """WGS-84 geodetic (degrees, degrees, metres) to ECEF, m."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    n = A_WGS84 / math.sqrt(1.0 - E2_WGS84 * math.sin(lat) ** 2)
    return (
        (n + h_m) * math.cos(lat) * math.cos(lon),
        (n + h_m) * math.cos(lat) * math.sin(lon),
        (n * (1.0 - E2_WGS84) + h_m) * math.sin(lat),
    )


def enu_error(p, truth_ecef, truth_llh):
    """(horizontal, vertical signed) error of ECEF `p` at the truth position, m."""
    d = [p[k] - truth_ecef[k] for k in range(3)]
    lat, lon = math.radians(truth_llh[0]), math.radians(truth_llh[1])
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    east = -so * d[0] + co * d[1]
    north = -sl * co * d[0] - sl * so * d[1] + cl * d[2]
    up = cl * co * d[0] + cl * so * d[1] + sl * d[2]
    return math.hypot(east, north), up


def rinex_float(text):
    text = text.strip().replace("D", "E").replace("d", "e")
    return float(text) if text else 0.0


def parse_rinex3_gps_nav(path):
    """GPS records of a RINEX 3 navigation file: {prn: [dict in the truth file's names]}."""
    with open(path, encoding="ascii", errors="replace") as f:
        lines = f.read().splitlines()
    body = next(i for i, l in enumerate(lines) if "END OF HEADER" in l) + 1
    records = {}
    i = body
    while i < len(lines):
        line = lines[i]
        if not line.startswith("G") or len(line) < 23:
            i += 1
            continue
        block = lines[i:i + 8]
        if len(block) < 8:
            break
        prn = int(line[1:3])

        def v(row, col):
            text = block[row][4 + 19 * col:4 + 19 * (col + 1)] if row else block[0][23 + 19 * col:23 + 19 * (col + 1)]
            return rinex_float(text)

        rec = {
            "prn": prn,
            "af0": v(0, 0), "af1": v(0, 1), "af2": v(0, 2),
            "iode": v(1, 0), "crs": v(1, 1), "delta_n": v(1, 2), "m0": v(1, 3),
            "cuc": v(2, 0), "e": v(2, 1), "cus": v(2, 2), "sqrt_a": v(2, 3),
            "toe_s": v(3, 0), "cic": v(3, 1), "omega0": v(3, 2), "cis": v(3, 3),
            "i0": v(4, 0), "crc": v(4, 1), "omega": v(4, 2), "omega_dot": v(4, 3),
            "idot": v(5, 0), "week": v(5, 2),
            "tgd": v(6, 2), "iodc": v(6, 3),
        }
        records.setdefault(prn, []).append(rec)
        i += 8
    return records


def find_rinex_nav(out_dir):
    for path in sorted(glob.glob(os.path.join(out_dir, "**", "*"), recursive=True)):
        if not os.path.isfile(path):
            continue
        try:
            with open(path, encoding="ascii", errors="replace") as f:
                head = f.readline()
        except OSError:
            continue
        if "RINEX VERSION" in head and ("NAVIGATION" in head or "N: GNSS NAV" in head or " N " in head[20:41]):
            return path
    return None


def compare_ephemerides(truth_ephs, decoded):
    """Per field, the worst |decoded - truth| in LSB over all PRNs; PRNs missing."""
    worst = {k: 0.0 for k in LSB}
    missing = []
    for t in truth_ephs:
        candidates = decoded.get(t["prn"], [])
        match = [d for d in candidates if int(round(d["iode"])) == t["iode"]]
        if not match:
            missing.append(t["prn"])
            continue
        d = match[-1]
        for key, lsb in LSB.items():
            tv = float(t[key])
            dv = d[key]
            if key == "week":
                diff = abs((int(round(dv)) - int(tv)) % 1024)
                diff = min(diff, 1024 - diff)
            else:
                # RINEX prints 12 decimals of mantissa: allow that rounding beside one LSB.
                diff = max(0.0, abs(dv - tv) - 1e-12 * abs(tv))
            worst[key] = max(worst[key], diff / lsb)
    return worst, missing


def parse_rinex3_obs_cn0(path):
    """{prn: [S1C, dB-Hz]} of a RINEX 3 GPS observation file."""
    with open(path, encoding="ascii", errors="replace") as f:
        lines = f.read().splitlines()
    types = []
    for l in lines:
        if "SYS / # / OBS TYPES" in l and l.startswith("G"):
            types = l[7:60].split()
        if "END OF HEADER" in l:
            break
    if "S1C" not in types:
        return {}
    k = types.index("S1C")
    body = next(i for i, l in enumerate(lines) if "END OF HEADER" in l) + 1
    cn0 = {}
    for l in lines[body:]:
        if l.startswith("G") and len(l) >= 3 + 16 * k + 14:
            text = l[3 + 16 * k:3 + 16 * k + 14].strip()
            if text:
                cn0.setdefault(int(l[1:3]), []).append(float(text))
    return cn0


def parse_rx_clock_offsets(path):
    """RTKLIB's receiver clock offsets (s) from GNSS-SDR's glog INFO file, after its whole-ms
    correction of the receiver time (|offset| < 1 ms)."""
    values = []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            m = re.search(r"RX time offset= *([-+0-9.eE]+) *\[s\]", line)
            if m and abs(float(m.group(1))) < 1e-3:
                values.append(float(m.group(1)))
    return values


def sod(hhmmss):
    h, m, s = int(hhmmss[0:2]), int(hhmmss[2:4]), float(hhmmss[4:])
    return 3600 * h + 60 * m + s


def parse_gga(path):
    """[(utc seconds of day, lat, lon, ellipsoidal height, pdop)] of the GGA sentences with a
    fix; the PDOP is the one of the GSA sentence that follows the GGA (None if absent)."""
    fixes = []
    with open(path, encoding="ascii", errors="replace") as f:
        for line in f:
            line = line.strip()
            if re.match(r"^\$G[PNL]GSA,", line) and fixes and fixes[-1][4] is None:
                fields = line.split("*")[0].split(",")
                if len(fields) > 15 and fields[15]:
                    fixes[-1] = fixes[-1][:4] + (float(fields[15]),)
                continue
            if not re.match(r"^\$G[PNL]GGA,", line):
                continue
            fields = line.split("*")[0].split(",")
            if len(fields) < 12 or not fields[2] or fields[6] in ("", "0"):
                continue
            lat = int(fields[2][:2]) + float(fields[2][2:]) / 60.0
            if fields[3] == "S":
                lat = -lat
            lon = int(fields[4][:3]) + float(fields[4][3:]) / 60.0
            if fields[5] == "W":
                lon = -lon
            alt = float(fields[9] or 0.0)
            sep = float(fields[11] or 0.0)
            fixes.append((sod(fields[1]), lat, lon, alt + sep, None))
    return fixes


def parse_kml(path):
    """[(lon, lat, h)] of a KML file's coordinates."""
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    points = []
    for block in re.findall(r"<coordinates>(.*?)</coordinates>", text, re.S):
        for triple in block.split():
            parts = triple.split(",")
            if len(parts) >= 2:
                points.append(tuple(float(x) for x in parts[:3]) + (0.0,) * (3 - len(parts[:3])))
    return points


def summary(errors, ttff):
    h = [e[0] for e in errors]
    v = [abs(e[1]) for e in errors]
    return {
        "fixes": len(errors),
        "ttff_s": ttff,
        "median_h_m": statistics.median(h) if h else None,
        "median_v_m": statistics.median(v) if v else None,
        "worst_h_m": max(h) if h else None,
        "worst_v_m": max(v) if v else None,
        "worst_3d_m": max(math.hypot(a, b) for a, b in errors) if errors else None,
    }


def fmt(x, digits=1):
    return "-" if x is None else f"{x:.{digits}f}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--truth", required=True)
    ap.add_argument("--pvt-dir", required=True)
    ap.add_argument("--nmea", required=True)
    ap.add_argument("--track", required=True)
    ap.add_argument("--install-s", type=float, default=0.0)
    ap.add_argument("--run-s", type=float, required=True)
    ap.add_argument("--track-s", type=float, required=True)
    ap.add_argument("--leap-s", type=float, default=18.0)
    ap.add_argument("--glog", help="GNSS-SDR's glog INFO file (receiver clock offsets)")
    ap.add_argument("--json-out")
    a = ap.parse_args()

    truth = json.load(open(a.truth))
    nav = truth["navigation"] if "navigation" in truth else truth
    t_ecef = nav["position_ecef_m"]
    t_llh = nav["position_llh"]
    tow0 = nav["tow_s"]
    failures = []

    # Ephemerides.
    rinex = find_rinex_nav(a.pvt_dir)
    decoded = parse_rinex3_gps_nav(rinex) if rinex else {}
    worst, missing = compare_ephemerides(nav["ephemerides"], decoded)
    n_sent = len(nav["ephemerides"])
    n_decoded = n_sent - len(missing)
    print(f"GNSS-SDR RINEX navigation file: {rinex or 'none'}")
    print(f"ephemerides: {n_decoded} of {n_sent} encoded PRNs decoded by GNSS-SDR"
          + (f" (missing {missing})" if missing else ""))
    print("worst |GNSS-SDR - truth| per field, LNAV LSB: " + ", ".join(f"{k} {worst[k]:.2f}" for k in LSB))
    if n_decoded == 0:
        failures.append("GNSS-SDR decoded no ephemeris")
    bad = [k for k, w in worst.items() if w > 1.0]
    if bad:
        failures.append(f"ephemeris fields beyond 1 LSB: {bad}")

    # GNSS-SDR fixes (NMEA GGA).
    gga = parse_gga(a.nmea) if os.path.exists(a.nmea) else []
    sdr_err = [enu_error(ecef_from_llh(lat, lon, h), t_ecef, t_llh) for _, lat, lon, h, _ in gga]
    start_sod = tow0 % 86400.0
    sdr_ttff = ((gga[0][0] + a.leap_s - start_sod) % 86400.0) if gga else None
    sdr = summary(sdr_err, sdr_ttff)
    # The 15 m check holds every fix of usable geometry (PDOP <= PDOP_GATE): a 4-satellite fix
    # at PDOP 5.6 with ~1.5 m code noise is ~8 m (1 sigma) by geometry alone.
    gated = [math.hypot(*e) for e, g in zip(sdr_err, gga) if g[4] is not None and g[4] <= PDOP_GATE]
    sdr["fixes_pdop_gated"] = len(gated)
    sdr["worst_3d_m_pdop_gated"] = max(gated, default=None)
    print(f"GNSS-SDR GGA fixes: {len(gga)}, {len(gated)} with PDOP <= {PDOP_GATE}; worst 3-D error "
          f"{fmt(sdr['worst_3d_m'])} m (all), {fmt(sdr['worst_3d_m_pdop_gated'])} m (PDOP <= {PDOP_GATE})")
    if not gated:
        failures.append(f"GNSS-SDR wrote no GGA fix with PDOP <= {PDOP_GATE}")
    elif sdr["worst_3d_m_pdop_gated"] > LIMIT_M:
        failures.append(f"a GNSS-SDR fix (PDOP <= {PDOP_GATE}) is {sdr['worst_3d_m_pdop_gated']:.1f} m from the truth (limit {LIMIT_M} m)")

    # GNSS-SDR KML track.
    kmls = glob.glob(os.path.join(a.pvt_dir, "**", "*.kml"), recursive=True)
    kml_points = [p for k in kmls for p in parse_kml(k)]
    kml_err = [enu_error(ecef_from_llh(lat, lon, h), t_ecef, t_llh) for lon, lat, h in kml_points]
    kml_3d = [math.hypot(*e) for e in kml_err]
    kml_worst = max(kml_3d, default=None)
    kml_median = statistics.median(kml_3d) if kml_3d else None
    print(f"KML: {len(kml_points)} points in {len(kmls)} file(s), 3-D error median {fmt(kml_median)} m, worst {fmt(kml_worst)} m")
    if not kml_points:
        failures.append("GNSS-SDR wrote no KML point")
    elif kml_median > LIMIT_M:
        failures.append(f"GNSS-SDR's KML track is {kml_median:.1f} m (median) from the truth")

    # Time: the synthesizer's sample clock is GPS time, so the receiver clock offset RTKLIB
    # estimates (after GNSS-SDR's whole-millisecond correction) is how far the encoded time
    # (TOW, code phase, satellite clock) is from the truth's.
    offsets = parse_rx_clock_offsets(a.glog) if a.glog and os.path.exists(a.glog) else []
    clock = {
        "epochs": len(offsets),
        "median_ns": statistics.median(offsets) * 1e9 if offsets else None,
        "sigma_ns": statistics.pstdev(offsets) * 1e9 if offsets else None,
    }
    print(f"GNSS-SDR receiver clock offset vs GPS time (the synthesizer's sample clock): median "
          f"{fmt(clock['median_ns'], 2)} ns, sigma {fmt(clock['sigma_ns'], 1)} ns over {clock['epochs']} solutions")
    if offsets and abs(clock["median_ns"]) > CLOCK_LIMIT_NS:
        failures.append(f"receiver clock offset {clock['median_ns']:.0f} ns (limit {CLOCK_LIMIT_NS} ns)")

    # C/N0: GNSS-SDR's estimate (RINEX S1C) against the synthesized one.
    obs = glob.glob(os.path.join(a.pvt_dir, "**", "*.*O"), recursive=True)
    cn0 = parse_rinex3_obs_cn0(obs[0]) if obs else {}
    truth_cn0 = {s["prn"]: s["cn0_dbhz"] for s in truth.get("satellites", [])}
    cn0_err = {prn: statistics.median(v) - truth_cn0[prn] for prn, v in cn0.items() if prn in truth_cn0}
    if cn0_err:
        print("GNSS-SDR C/N0 (median S1C) minus synthesized, dB: "
              + ", ".join(f"G{prn:02} {e:+.2f}" for prn, e in sorted(cn0_err.items())))
        worst_cn0 = max(abs(e) for e in cn0_err.values())
        if worst_cn0 > CN0_LIMIT_DB:
            failures.append(f"GNSS-SDR's C/N0 is {worst_cn0:.1f} dB off the synthesized (limit {CN0_LIMIT_DB} dB)")

    # host-sim track --json on the same file.
    track = json.load(open(a.track))
    tn = track.get("navigation") or {}
    hs_err = [enu_error(f["position_ecef_m"], t_ecef, t_llh) for f in tn.get("per_fix", [])]
    hs = summary(hs_err, tn.get("ttff_s"))

    print()
    print(f"{'receiver':<34} {'run s':>7} {'fixes':>6} {'TTFF s':>7} {'med H m':>8} {'med V m':>8} {'worst H m':>9} {'worst V m':>9}")
    for name, s, run in (("GNSS-SDR 0.0.17 (RTKLIB single)", sdr, a.run_s),
                         ("host-sim track --json (no --sky)", hs, a.track_s)):
        print(f"{name:<34} {run:>7.1f} {s['fixes']:>6} {fmt(s['ttff_s']):>7} {fmt(s['median_h_m'], 2):>8} "
              f"{fmt(s['median_v_m'], 2):>8} {fmt(s['worst_h_m'], 2):>9} {fmt(s['worst_v_m'], 2):>9}")
    print(f"GNSS-SDR install {a.install_s:.0f} s, run {a.run_s:.1f} s")

    result = {
        "install_s": a.install_s,
        "gnss_sdr": dict(sdr, run_s=a.run_s, kml_points=len(kml_points), kml_median_3d_m=kml_median, kml_worst_3d_m=kml_worst),
        "host_sim_track": dict(hs, run_s=a.track_s),
        "rx_clock_offset": clock,
        "cn0_minus_synthesized_db": {f"G{p:02}": e for p, e in sorted(cn0_err.items())},
        "ephemerides_sent": n_sent,
        "ephemerides_decoded": n_decoded,
        "ephemeris_worst_lsb": worst,
        "failures": failures,
        "ok": not failures,
    }
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump(result, f, indent=1)
    for msg in failures:
        print(f"FAIL: {msg}")
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main())
