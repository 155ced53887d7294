#!/usr/bin/env python3
"""Before/after comparison of builds on this machine's terms: interleaved rounds, medians.

The VMs this project runs on change speed by 20-30 % from hour to hour, so two builds are only
compared within one run: each round runs every build once per filter (the builds' order reversed
every other round, so neither always runs first), and the table gives each counter's median over
the rounds, every round's value of the first counter, and the ratio of medians to the first build.

  bench/ab.py --build before=/tmp/b0 --build after=build --bench bench_engine \\
      --filter 'BM_DenseFilmSteps' --rounds 5 --counters element_steps_per_s,pair_ms

A build is a CMake build directory (its programs in <dir>/bench/). --env sets variables for the
runs (e.g. OMP_WAIT_POLICY=PASSIVE, MDEM_TENSILE_FILM_DIR=...); --out keeps every run's JSON.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
from collections import defaultdict


def checked_rounds_and_env(ap, a):
    """Refuses --rounds outside 1..1000 and an --env without KEY=; the runs' environment."""
    if a.rounds < 1 or a.rounds > 1000:
        ap.error(f"--rounds {a.rounds}: expected 1 to 1000")
    env = dict(os.environ)
    for e in a.env:
        k, sep, v = e.partition("=")
        if not sep or not k:
            ap.error(f"--env {e!r}: expected KEY=VALUE")
        env[k] = v
    return env


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", action="append", required=True, metavar="NAME=DIR",
                    help="a build to compare (repeat; the first is the reference)")
    ap.add_argument("--bench", required=True, help="benchmark program, e.g. bench_engine")
    ap.add_argument("--filter", action="append", required=True,
                    help="--benchmark_filter regex (repeat for several runs per round)")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default 3)")
    ap.add_argument("--counters", default="element_steps_per_s",
                    help="comma-separated counters to report (default element_steps_per_s)")
    ap.add_argument("--env", action="append", default=[], metavar="KEY=VALUE",
                    help="environment for the runs (repeat)")
    ap.add_argument("--out", help="directory to keep each run's JSON in")
    a = ap.parse_args(argv)
    builds = []
    for b in a.build:
        name, sep, path = b.partition("=")
        if not sep or not name or not path:
            ap.error(f"--build {b!r}: expected NAME=DIR")
        prog = os.path.join(path, "bench", a.bench)
        if not os.access(prog, os.X_OK):
            ap.error(f"--build {b!r}: no executable {prog}")
        builds.append((name, prog))
    if len({n for n, _ in builds}) != len(builds):
        ap.error("--build names must differ")
    env = checked_rounds_and_env(ap, a)
    counters = [c for c in a.counters.split(",") if c]
    if not counters:
        ap.error("--counters: name at least one counter")
    return a, builds, env, counters


def benchmark_json(cmd, out, err, code, tool="ab.py"):
    """The benchmarks of a Google Benchmark run's JSON output; exits naming what went wrong."""
    if code != 0:
        sys.exit(f"{tool}: {' '.join(cmd)} failed (exit {code}):\n{err[-2000:]}")
    if not out.strip():
        sys.exit(f"{tool}: {' '.join(cmd)}: no output (does the filter match a benchmark?)\n"
                 f"{err[-2000:]}")
    try:
        return json.loads(out)["benchmarks"]
    except (ValueError, KeyError) as e:
        sys.exit(f"{tool}: {' '.join(cmd)}: no benchmark JSON on stdout ({e})")


def run_once(prog, flt, env):
    cmd = [prog, f"--benchmark_filter={flt}", "--benchmark_format=json"]
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    return p.stdout, benchmark_json(cmd, p.stdout, p.stderr, p.returncode)


def main(argv):
    a, builds, env, counters = parse_args(argv)
    values = defaultdict(list)  # (benchmark, build, counter) -> one value per round
    names = []
    for r in range(a.rounds):
        order = builds if r % 2 == 0 else builds[::-1]
        for name, prog in order:
            for k, flt in enumerate(a.filter):
                raw, results = run_once(prog, flt, env)
                if a.out:
                    os.makedirs(a.out, exist_ok=True)
                    with open(os.path.join(a.out, f"{name}.{r + 1}.{k + 1}.json"), "w") as f:
                        f.write(raw)
                for b in results:
                    if b.get("run_type") == "aggregate":
                        continue
                    if b["name"] not in names:
                        names.append(b["name"])
                    for c in counters:
                        v = b.get(c)
                        if v is not None:
                            values[(b["name"], name, c)].append(float(v))
        print(f"round {r + 1} of {a.rounds} done", file=sys.stderr)
    if not names:
        sys.exit("ab.py: the filters matched no benchmark")
    ref = builds[0][0]
    print(f"medians of {a.rounds} interleaved rounds; ratio = median / {ref}'s")
    for bench in names:
        print(bench)
        for name, _ in builds:
            cols = []
            for c in counters:
                v = values.get((bench, name, c))
                if not v:
                    cols.append(f"{c} -")
                    continue
                med = statistics.median(v)
                col = f"{c} {med:.4g}"
                rv = values.get((bench, ref, c))
                if name != ref and rv:
                    col += f" ({med / statistics.median(rv):.3f})"
                cols.append(col)
            first = values.get((bench, name, counters[0]), [])
            rounds = ", ".join(f"{x:.3g}" for x in first)
            print(f"  {name:12s} " + "  ".join(cols) + f"   [{counters[0]} by round: {rounds}]")


if __name__ == "__main__":
    main(sys.argv[1:])
