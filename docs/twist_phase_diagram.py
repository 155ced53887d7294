#!/usr/bin/env python3
"""The morphology phase diagram of twisted ropes (docs/twist.md, "Morphology phase diagram").

Reads the twist jobs of one or more studies (`mdem study twist --vary length=...,torque=...`)
from an mdem results database and prints, per run, the aspect ratio gamma = L/R0 (L the tubes'
length from the spec, R0 the rope's initial radius the job measured), the torque, the outcome and
morphology at the end, when the rope first left the straight and spindle shapes (bird cage,
helix or separated), the e-folding time of beta while it grows from the noise, beta, Q, R, and whether the run settled: bending energy within 5 % (or within 10 eV,
a straight rope's noise), beta within 0.5 deg and Q constant over the last 100 ps. With --png it draws gamma against
torque with one symbol per end morphology, by gnuplot.

Only the standard library is used (sqlite3); the picture needs gnuplot on the PATH.

  python3 docs/twist_phase_diagram.py --db results.db s-ID1 [s-ID2 ...] [--png out.png]
"""
import argparse
import json
import math
import os
import sqlite3
import struct
import subprocess
import sys
import tempfile

SEGMENT_NM = 1.356  # spec::kSegmentNm: a tube's length is a whole number of these
NAMES = ["straight", "spindle", "bird cage", "helix", "separated"]  # morphology_code 0..4
SETTLE_WINDOW_PS = 100.0
SETTLE_REL = 0.05
SETTLE_ABS_EV = 10.0
SETTLE_BETA_DEG = 0.5
GROWTH_BETA_DEG = (0.05, 2.0)  # the window of beta in which its growth is fitted as exponential
GROWTH_MIN_SPAN_PS = 40.0


def growth_time(series):
    """e-folding time (ps) of the twist angle beta while it grows from the noise: a least-squares
    line through ln(beta) over the frames with beta in GROWTH_BETA_DEG before it first leaves that
    window upward; None when beta never spans GROWTH_MIN_SPAN_PS in the window or does not grow."""
    pts = []
    for r in series:
        b = r["twist_angle_deg"]
        if b > GROWTH_BETA_DEG[1]:
            break
        if b >= GROWTH_BETA_DEG[0]:
            pts.append((r["time_ps"], math.log(b)))
    if len(pts) < 5 or pts[-1][0] - pts[0][0] < GROWTH_MIN_SPAN_PS:
        return None
    n = len(pts)
    mt = sum(t for t, _ in pts) / n
    my = sum(y for _, y in pts) / n
    sxx = sum((t - mt) ** 2 for t, _ in pts)
    slope = sum((t - mt) * (y - my) for t, y in pts) / sxx
    return 1.0 / slope if slope > 0 else None


def frames(db, job_id, columns):
    """The job's series as a list of dicts (time_ps plus the named columns)."""
    out = []
    idx = {c: i for i, c in enumerate(columns)}
    for t, vals in db.execute("SELECT time_ps, vals FROM frames WHERE job_id = ? ORDER BY seq",
                              (job_id,)):
        n = len(vals) // 8
        v = struct.unpack("<%dd" % n, vals)
        row = {"time_ps": t}
        for c, i in idx.items():
            if i < n:
                row[c] = v[i]
        out.append(row)
    return out


def settled(series, end_ps):
    """(bool, words): bending within 5 % (or 10 eV), beta within 0.5 deg and Q constant over the
    last 100 ps."""
    if not series or end_ps - series[0]["time_ps"] < SETTLE_WINDOW_PS:
        return False, "too short"
    win = [r for r in series if r["time_ps"] >= end_ps - SETTLE_WINDOW_PS]
    b = [r["bond_bending_eV"] for r in win]
    q = {int(round(r["topological_charge"])) for r in win}
    spread = max(b) - min(b)
    ok_b = spread <= max(SETTLE_REL * max(abs(x) for x in b), SETTLE_ABS_EV)
    ok_q = len(q) == 1
    be = [r["twist_angle_deg"] for r in win]
    ok_beta = max(be) - min(be) <= SETTLE_BETA_DEG
    if ok_b and ok_q and ok_beta:
        return True, "yes"
    why = []
    if not ok_b:
        why.append("bending %.3g to %.3g eV" % (min(b), max(b)))
    if not ok_beta:
        why.append("β %.1f to %.1f°" % (min(be), max(be)))
    if not ok_q:
        why.append("Q %d to %d" % (min(q), max(q)))
    return False, "no: " + ", ".join(why)


def rows(db, study_ids):
    out = []
    for sid in study_ids:
        q = db.execute(
            "SELECT r.seq, r.job_id, j.state, j.spec_json, j.summary_json, j.columns_json "
            "FROM study_runs AS r LEFT JOIN jobs AS j ON j.id = r.job_id "
            "WHERE r.study_id LIKE ? ORDER BY r.seq", (sid + "%",)).fetchall()
        if not q:
            sys.exit("no study %s in the database (mdem watch --study ID --server ... first)" % sid)
        for seq, job_id, state, spec_json, summary_json, columns_json in q:
            spec = json.loads(spec_json or "{}")
            tw = spec.get("twist", {})
            length = round(float(tw.get("lengthNm", tw.get("length_nm", 0))) / SEGMENT_NM)
            length *= SEGMENT_NM
            torque = float(tw.get("torqueNnNm", tw.get("torque_nn_nm", 0)))
            rate = float(tw.get("torqueRateNnNmPerPs", tw.get("torque_rate_nn_nm_per_ps", 1.0)))
            row = {"study": sid, "seq": seq, "job": job_id, "state": state or "not recorded",
                   "L": length, "T": torque, "rate": rate}
            doc = json.loads(summary_json) if summary_json else {}
            summ = doc.get("summary", {})
            row["wall_s"] = doc.get("performance", {}).get("wall_s")
            row["balance"] = doc.get("accuracy", {}).get("energy_balance_error")
            cols = json.loads(columns_json) if columns_json else []
            series = frames(db, job_id, cols) if cols else []
            row["summary"] = summ
            row["series"] = series
            out.append(row)
    return out


def describe(r):
    s, series = r["summary"], r["series"]
    r0 = s.get("initial_rope_radius_nm")
    if r0 is None and series:
        r0 = series[0].get("rope_radius_nm")
    r["R0"] = r0
    r["gamma"] = r["L"] / r0 if r0 else None
    if not series:
        return r
    last = series[-1]
    r["end_ps"] = last["time_ps"]
    ramp_end = r["T"] / r.get("rate", 1.0)
    r["code"] = int(round(last["morphology_code"]))
    r["morph"] = s.get("morphology", NAMES[r["code"]])
    r["outcome"] = s.get("outcome", "running" if r["state"] == "RUNNING" else "")
    r["beta"] = last["twist_angle_deg"]
    r["Q"] = int(round(last["topological_charge"]))
    r["Qmax"] = max(int(round(x["topological_charge"])) for x in series)
    r["R"] = last["rope_radius_nm"]
    r["torsion_peak"] = max(x["bond_torsion_eV"] for x in series)
    r["torsion_end"] = last["bond_torsion_eV"]
    r["bending_end"] = last["bond_bending_eV"]
    first = next((x["time_ps"] for x in series if x["morphology_code"] >= 1.5), None)
    r["tau"] = growth_time(series)
    r["onset"] = None if first is None else first - ramp_end  # ps into the hold (negative: ramp)
    if r["outcome"] == "separated_by_over_twist":
        r["settled"] = "ended by the separation"
    elif r["state"] != "SUCCEEDED":
        r["settled"] = "(not finished)"
    else:
        r["settled"] = settled(series, r["end_ps"])[1]
    return r


def markdown(table):
    print("| γ = L/R₀ | L (nm) | T (nN·nm) | state, end (ps) | outcome, morphology | cage/helix "
          "from (ps into the hold) | β e-folding (ps) | β end (°) | Q end / max | R end (nm) | torsion peak → end, "
          "bending end (eV) | settled? | balance error | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in table:
        g = "%.2f" % r["gamma"] if r.get("gamma") else "?"
        if "end_ps" not in r:
            print("| %s | %.2f | %g | %s | | | | | | | | | | |" % (g, r["L"], r["T"], r["state"]))
            continue
        onset = "—" if r["onset"] is None else "%.0f" % r["onset"]
        tau = "—" if r["tau"] is None else "%.0f" % r["tau"]
        bal = "" if r.get("balance") is None else "%.1e" % r["balance"]
        wall = "" if r.get("wall_s") is None else "%.0f" % r["wall_s"]
        print("| %s | %.2f | %g | %s, %.0f | %s, %s | %s | %s | %.1f | %d / %d | %.2f | %.3g → %.3g, %.3g "
              "| %s | %s | %s |" % (g, r["L"], r["T"], r["state"], r["end_ps"], r["outcome"],
                                    r["morph"], onset, tau, r["beta"], r["Q"], r["Qmax"], r["R"],
                                    r["torsion_peak"], r["torsion_end"], r["bending_end"],
                                    r["settled"], bal, wall))


def plot(table, png, title):
    """gamma against torque, one symbol per end state (a separation over any morphology), a cross
    over runs still changing at the end, the thesis's regions of Fig. 4-11 behind."""
    styles = [("straight", 6, 0x808080), ("spindle", 7, 0x3070c0), ("bird cage", 9, 0xe07090),
              ("helix", 5, 0x202020), ("separated by over twist", 3, 0xc03020)]
    classes = [[] for _ in styles]
    unsettled, unfinished = [], []
    for r in table:
        if not r.get("gamma"):
            continue
        if r["state"] != "SUCCEEDED" or "code" not in r:
            unfinished.append(r)
            continue
        c = 4 if r["outcome"] == "separated_by_over_twist" else r["code"]
        classes[c].append(r)
        if not r["settled"].startswith(("yes", "ended")):
            unsettled.append(r)
    with tempfile.TemporaryDirectory() as d:
        series = []
        for i, (name, pt, col) in enumerate(styles):
            series.append((classes[i], 'pt %d ps 2.2 lc rgb "#%06x"' % (pt, col), name))
        series.append((unsettled, 'pt 2 ps 3.2 lc rgb "#e0a000" lw 2', "still changing at the end"))
        series.append((unfinished, 'pt 1 ps 2.5 lc rgb "#000000"', "not finished"))
        parts = []
        for i, (rows_, style, name) in enumerate(series):
            if not rows_:
                continue
            dat = os.path.join(d, "p%d.dat" % i)
            with open(dat, "w") as f:
                for r in rows_:
                    f.write("%g %g\n" % (r["gamma"], r["T"]))
            parts.append('"%s" using 1:2 with points %s title "%s"' % (dat, style, name))
        gp = os.path.join(d, "p.gp")
        with open(gp, "w") as f:
            f.write('set terminal pngcairo size 900,640 font ",11"\nset output "%s"\n' % png)
            f.write('set xlabel "aspect ratio γ = L/R_0"\nset ylabel "torque per grip element '
                    '(nN·nm)"\nset logscale x\nset xrange [4:30]\nset yrange [20:95]\n'
                    'set xtics (5, 8, 12, 16, 24)\nset key below horizontal\nset grid\n'
                    'set title "%s"\n' % title)
            # The thesis's Fig. 4-11 regions, as its text states them.
            f.write('set object 1 rect from 4,20 to 8,95 fc rgb "#ffd0dc" fs solid 0.5 '
                    'noborder behind\n')
            f.write('set object 2 rect from 8,20 to 15,85 fc rgb "#d0e8ff" fs solid 0.5 '
                    'noborder behind\n')
            f.write('set label 1 "thesis: bird cage" at 4.3,22 font ",9"\n')
            f.write('set label 2 "thesis: stable spindle" at 8.4,22 font ",9"\n')
            f.write('set label 3 "thesis: helix above T_c ∝ γ^{-0.36}" at 15.5,22 font ",9"\n')
            f.write("plot " + ", \\\n     ".join(parts) + "\n")
        subprocess.run(["gnuplot", gp], check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("studies", nargs="+", help="study ids (a prefix is enough)")
    ap.add_argument("--db", default=os.environ.get("MDEM_DB",
                    os.path.expanduser("~/.local/share/mdem/results.db")))
    ap.add_argument("--png", help="draw the diagram into this PNG (gnuplot)")
    ap.add_argument("--title", default="Twisted N = 4 rope, per-element load: state at the end")
    a = ap.parse_args()
    if not os.path.exists(a.db):
        sys.exit("--db: no file %s" % a.db)
    db = sqlite3.connect("file:%s?mode=ro" % a.db, uri=True)
    table = [describe(r) for r in rows(db, a.studies)]
    table.sort(key=lambda r: (r["L"], r["T"]))
    markdown(table)
    if a.png:
        plot(table, a.png, a.title)


if __name__ == "__main__":
    main()
