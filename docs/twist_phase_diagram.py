#!/usr/bin/env python3
"""The morphology phase diagram of twisted ropes (docs/twist.md, "Morphology phase diagram").

Reads the twist jobs of one or more studies (`mdem study twist --vary length=...,torque=...`)
from an mdem results database and prints, per run, the aspect ratio gamma = L/R0 (L the tubes'
length from the spec, R0 the rope's initial radius the job measured), the torque, the outcome and
morphology at the end, when the rope first left the straight and spindle shapes (bird cage,
helix or separated), beta, Q, R, and whether the run settled: bending energy within 5 % (or within 10 eV,
a straight rope's noise) and Q constant over the last 100 ps. With --png it draws gamma against
torque with one symbol per end morphology, by gnuplot.

Only the standard library is used (sqlite3); the picture needs gnuplot on the PATH.

  python3 docs/twist_phase_diagram.py --db results.db s-ID1 [s-ID2 ...] [--png out.png]
"""
import argparse
import json
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
    """(bool, words): bending within 5 % (or 10 eV) and Q constant over the last 100 ps."""
    if not series or end_ps - series[0]["time_ps"] < SETTLE_WINDOW_PS:
        return False, "too short"
    win = [r for r in series if r["time_ps"] >= end_ps - SETTLE_WINDOW_PS]
    b = [r["bond_bending_eV"] for r in win]
    q = {int(round(r["topological_charge"])) for r in win}
    spread = max(b) - min(b)
    ok_b = spread <= max(SETTLE_REL * max(abs(x) for x in b), SETTLE_ABS_EV)
    ok_q = len(q) == 1
    if ok_b and ok_q:
        return True, "yes"
    why = []
    if not ok_b:
        why.append("bending %.3g to %.3g eV" % (min(b), max(b)))
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
          "from (ps into the hold) | β end (°) | Q end / max | R end (nm) | torsion peak → end, "
          "bending end (eV) | settled? | balance error | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in table:
        g = "%.2f" % r["gamma"] if r.get("gamma") else "?"
        if "end_ps" not in r:
            print("| %s | %.2f | %g | %s | | | | | | | | | |" % (g, r["L"], r["T"], r["state"]))
            continue
        onset = "—" if r["onset"] is None else "%.0f" % r["onset"]
        bal = "" if r.get("balance") is None else "%.1e" % r["balance"]
        wall = "" if r.get("wall_s") is None else "%.0f" % r["wall_s"]
        print("| %s | %.2f | %g | %s, %.0f | %s, %s | %s | %.1f | %d / %d | %.2f | %.3g → %.3g, %.3g "
              "| %s | %s | %s |" % (g, r["L"], r["T"], r["state"], r["end_ps"], r["outcome"],
                                    r["morph"], onset, r["beta"], r["Q"], r["Qmax"], r["R"],
                                    r["torsion_peak"], r["torsion_end"], r["bending_end"],
                                    r["settled"], bal, wall))


def plot(table, png):
    styles = {0: ("straight", 6, 0x808080), 1: ("spindle", 7, 0x3070c0),
              2: ("bird cage", 9, 0xe07090), 3: ("helix", 5, 0x202020),
              4: ("separated (over twist)", 3, 0xc03020)}
    with tempfile.TemporaryDirectory() as d:
        dat = os.path.join(d, "p.dat")
        with open(dat, "w") as f:
            for code in range(5):
                f.write("# %s\n" % styles[code][0])
                for r in table:
                    if r.get("code") == code and r.get("gamma"):
                        f.write("%g %g\n" % (r["gamma"], r["T"]))
                f.write("\n\n")
            f.write("# not run / running\n")
            for r in table:
                if r.get("gamma") and r.get("state") not in ("SUCCEEDED",):
                    f.write("%g %g\n" % (r["gamma"], r["T"]))
        gp = os.path.join(d, "p.gp")
        with open(gp, "w") as f:
            f.write('set terminal pngcairo size 900,620 font ",11"\nset output "%s"\n' % png)
            f.write('set xlabel "aspect ratio γ = L/R_0"\nset ylabel "torque per grip element '
                    '(nN·nm)"\nset logscale x\nset xrange [4:30]\nset yrange [20:90]\n'
                    'set key outside right\nset grid\n'
                    'set title "Twisted N = 4 rope, per-element load: morphology at the end"\n')
            # The thesis's Fig. 4-11 regions, as its text states them.
            f.write('set object 1 rect from 4,20 to 8,90 fc rgb "#ffd0dc" fs solid 0.5 '
                    'noborder behind\n')
            f.write('set object 2 rect from 8,20 to 15,85 fc rgb "#d0e8ff" fs solid 0.5 '
                    'noborder behind\n')
            f.write('set label 1 "thesis: bird cage γ<8" at 4.3,87 font ",9"\n')
            f.write('set label 2 "thesis: stable spindle ≤ 85" at 8.3,82 font ",9"\n')
            f.write('set label 3 "thesis: helix γ>15" at 16,87 font ",9"\n')
            parts = []
            for code in range(5):
                name, pt, col = styles[code]
                parts.append('"%s" index %d using 1:2 with points pt %d ps 2.2 lc rgb "#%06x" '
                             'title "%s"' % (dat, code, pt, col, name))
            parts.append('"%s" index 5 using 1:2 with points pt 1 ps 2.5 lc rgb "#000000" '
                         'title "not finished"' % dat)
            f.write("plot " + ", \\\n     ".join(parts) + "\n")
        subprocess.run(["gnuplot", gp], check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("studies", nargs="+", help="study ids (a prefix is enough)")
    ap.add_argument("--db", default=os.environ.get("MDEM_DB",
                    os.path.expanduser("~/.local/share/mdem/results.db")))
    ap.add_argument("--png", help="draw the diagram into this PNG (gnuplot)")
    a = ap.parse_args()
    if not os.path.exists(a.db):
        sys.exit("--db: no file %s" % a.db)
    db = sqlite3.connect("file:%s?mode=ro" % a.db, uri=True)
    table = [describe(r) for r in rows(db, a.studies)]
    table.sort(key=lambda r: (r["L"], r["T"]))
    markdown(table)
    if a.png:
        plot(table, a.png)


if __name__ == "__main__":
    main()
