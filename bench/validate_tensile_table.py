#!/usr/bin/env python3
"""Tables of the tensile validation runs (bench/validate_tensile_films.sh OUTDIR).

Usage: bench/validate_tensile_table.py OUTDIR

Reads OUTDIR/runs.tsv and each run's report (<name>.txt, validate_tensile film's summary lines)
and prints Markdown: every run, the mean ± sample standard deviation over seeds per film side and
case, the per-seed ratios (ready-to-relax / relaxed, with NPs / pristine) and the cyclic run's
cycles. Numbers only from the reports; nothing is fitted or adjusted.
"""
import math
import os
import sys
from collections import defaultdict


def read_report(path):
    vals = {}
    with open(path) as f:
        for line in f:
            if line.startswith("  wall "):  # "  wall 24.8 s on 1 thread(s), 2100 elements, 12415 steps"
                w = line.replace(",", "").split()
                vals["wall_s"] = float(w[1])  # the job's own (generation to summary)
                vals["steps"] = int(w[w.index("steps") - 1])
                vals["elements"] = int(w[w.index("elements") - 1])
                continue
            if not line.startswith("  ") or line.startswith("  stage "):
                continue
            parts = line.strip().split(None, 1)
            if len(parts) != 2:
                continue
            key, v = parts
            try:
                vals[key] = float(v)
            except ValueError:
                vals[key] = v
    return vals


def mean_sd(xs):
    xs = [x for x in xs if x is not None]
    if not xs:
        return None, None, 0
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) if len(xs) > 1 else float("nan")
    return m, sd, len(xs)


def fmt(m, sd, n, digits=2, scale=1.0):
    if m is None:
        return "–"
    if n < 2:
        return f"{m * scale:.{digits}f} (1 seed)"
    return f"{m * scale:.{digits}f} ± {sd * scale:.{digits}f} (n={n})"


def main():
    out = sys.argv[1]
    runs = []
    with open(os.path.join(out, "runs.tsv")) as f:
        for line in f:
            name, side, seed, case, wall, rc = line.rstrip("\n").split("\t")
            rep = read_report(os.path.join(out, name + ".txt"))
            runs.append(dict(name=name, side=int(float(side)), seed=int(seed), case=case,
                             wall=rep.get("wall_s", float(wall)), rc=int(rc), r=rep))

    print("| run | exit | E (GPa) | in tension at 2 % | NPs | prerelax dt → dt (fs) | steps | "
          "aligned pairs (registry-free) relax start → end | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for x in runs:
        r = x["r"]
        e = r.get("youngs_modulus_GPa")
        t = r.get("tubes_in_tension_at_2pct")
        dt0, dt = r.get("prerelax_dt_ps"), r.get("dt_ps")
        print(f"| {x['name']} | {x['rc']} | {e:.3f} |" if e is not None else f"| {x['name']} | {x['rc']} | – |",
              f"{100 * t:.1f} % |" if t is not None else "– |",
              f"{int(r.get('nanoparticles', 0))} |",
              f"{1000 * dt0:.2f} → {1000 * dt:.2f} |" if dt0 and dt else "– |",
              f"{r.get('steps', '–')} |",
              f"{int(r['relax_aligned_registry_free_start'])} → {int(r['relax_aligned_registry_free_end'])} |"
              if "relax_aligned_registry_free_end" in r else "– |",
              f"{x['wall']:.0f} |")

    by = defaultdict(list)
    for x in runs:
        if x["rc"] == 0:
            by[(x["side"], x["case"])].append(x)
    print()
    print("| side (nm) | case | E (GPa), mean ± sd | in tension at 2 % (%) | mean wall (s) |")
    print("|---|---|---|---|---|")
    for (side, case), xs in sorted(by.items()):
        if case == "cyclic":
            continue
        e = mean_sd([x["r"].get("youngs_modulus_GPa") for x in xs])
        t = mean_sd([x["r"].get("tubes_in_tension_at_2pct") for x in xs])
        w = sum(x["wall"] for x in xs) / len(xs)
        cv = f", CV {100 * e[1] / e[0]:.0f} %" if e[2] > 1 and e[0] else ""
        print(f"| {side} | {case} | {fmt(*e)}{cv} | {fmt(*t, digits=1, scale=100)} | {w:.0f} |")

    print()
    print("| side (nm) | ratio | per seed | mean ± sd |")
    print("|---|---|---|---|")
    sides = sorted({x["side"] for x in runs})
    for side in sides:
        for case, ref, label in (("ready", "relaxed", "E ready-to-relax / E relaxed"),
                                 ("nps", "relaxed", "E with NPs / E pristine (relaxed)"),
                                 ("ready_nps", "ready", "E with NPs / E pristine (ready-to-relax)")):
            per = []
            for x in runs:
                if x["side"] != side or x["case"] != case or x["rc"] != 0:
                    continue
                base = [y for y in runs if y["side"] == side and y["seed"] == x["seed"]
                        and y["case"] == ref and y["rc"] == 0]
                if not base:
                    continue
                a, b = x["r"].get("youngs_modulus_GPa"), base[0]["r"].get("youngs_modulus_GPa")
                if a is not None and b:
                    per.append((x["seed"], a / b))
            if per:
                m = mean_sd([p[1] for p in per])
                print(f"| {side} | {label} | " + ", ".join(f"{p[1]:.2f} (seed {p[0]})" for p in per)
                      + f" | {fmt(*m)} |")
        dt = [x["r"]["tubes_in_tension_at_2pct"] - y["r"]["tubes_in_tension_at_2pct"]
              for x in runs for y in runs
              if x["side"] == side == y["side"] and x["seed"] == y["seed"] and x["case"] == "nps"
              and y["case"] == "relaxed" and "tubes_in_tension_at_2pct" in x["r"]
              and "tubes_in_tension_at_2pct" in y["r"]]
        if dt:
            m = mean_sd(dt)
            print(f"| {side} | tubes in tension, NPs − pristine (points) | "
                  + ", ".join(f"{100 * d:+.1f}" for d in dt) + f" | {fmt(*m, digits=1, scale=100)} |")

    for x in runs:
        if x["case"] != "cyclic":
            continue
        r = x["r"]
        print()
        print(f"Cyclic run {x['name']} (exit {x['rc']}, wall {x['wall']:.0f} s):")
        print()
        print("| cycle | loop area (J/cm³) | modulus (GPa) | phase lead (% of P) |")
        print("|---|---|---|---|")
        k = 1
        while f"cycle_{k}_modulus_GPa" in r:
            print(f"| {k} | {r[f'cycle_{k}_loop_area_J_cm3']:.4f} | {r[f'cycle_{k}_modulus_GPa']:.3f} | "
                  f"{100 * r[f'cycle_{k}_phase_lead']:.2f} |")
            k += 1


if __name__ == "__main__":
    main()
