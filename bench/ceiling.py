#!/usr/bin/env python3
"""How close two threads come to what the machine gives two independent one-thread runs.

Two threads share one step: they meet at every phase's end, and run the passes over memory at
the same moment. Two copies of the one-thread benchmark, one per core, share only the machine
(memory, caches, the host's other tenants). Their summed rate over one copy alone is the
machine's ceiling for two streams of this work; the two-thread rate over it is what the step's
structure keeps of that. Each round runs, one after the other: the 1-thread benchmark alone,
two copies of it at once (pinned to CPUs 0 and 1 with taskset where it exists), the 2-thread
benchmark. Medians over the rounds, and every round's ratios (these VMs change speed by 20-30 %
from hour to hour, so only a round's own runs are compared). With --probe, each round starts
with bench_machine's placement figures: a cache line's round trip between the two threads, the
rate of reading what the other core just wrote against one's own (a VM's two CPUs may sit near
each other or far apart, and move between hours; docs/engine.md, "Five more tries"), and the
multiply-add rate two threads get at once over one alone's (~2 on two cores, ~1 on two hardware
threads of one core).

  bench/ceiling.py --build build --bench bench_tensile_film \\
      --one 'BM_RelaxedMediumFilm/threads:1/nps:1/order:0/' \\
      --two 'BM_RelaxedMediumFilm/threads:2/nps:1/order:2/' --rounds 7 \\
      --env MDEM_TENSILE_FILM_DIR=/tmp/film
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ab import benchmark_json, checked_rounds_and_env  # noqa: E402  (shared with ab.py)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", required=True, metavar="DIR", help="CMake build directory")
    ap.add_argument("--bench", required=True, help="benchmark program, e.g. bench_tensile_film")
    ap.add_argument("--one", required=True, help="--benchmark_filter of the 1-thread benchmark")
    ap.add_argument("--two", required=True, help="--benchmark_filter of the 2-thread benchmark")
    ap.add_argument("--rounds", type=int, default=5, help="rounds (default 5)")
    ap.add_argument("--counter", default="element_steps_per_s",
                    help="the rate to compare, higher is better (two copies' rates are "
                    "summed; not a time such as ns_per_element; default element_steps_per_s)")
    ap.add_argument("--phases", default="",
                    help="comma-separated per-step time counters to show too (e.g. pair_ms,"
                    "neighbor_ms,integrate_ms): medians for one alone, a copy (the two's mean), "
                    "2 threads")
    ap.add_argument("--env", action="append", default=[], metavar="KEY=VALUE",
                    help="environment for the runs (repeat)")
    ap.add_argument("--probe", action="store_true",
                    help="each round, first measure where the two CPUs sit (bench_machine's "
                    "BM_LineRoundTrip, BM_ReadAfterWrite and BM_FmaShare, from the same build)")
    a = ap.parse_args(argv)
    prog = os.path.join(a.build, "bench", a.bench)
    if not os.access(prog, os.X_OK):
        ap.error(f"--build {a.build!r}, --bench {a.bench!r}: no executable {prog}")
    a.machine = os.path.join(a.build, "bench", "bench_machine")
    if a.probe and not os.access(a.machine, os.X_OK):
        ap.error(f"--probe: no executable {a.machine} (build the bench_machine target)")
    if os.cpu_count() is None or os.cpu_count() < 2:
        ap.error("this machine has fewer than 2 CPUs: nothing to compare")
    return a, prog, checked_rounds_and_env(ap, a)


def command(prog, flt, cpu=None):
    cmd = [prog, f"--benchmark_filter={flt}", "--benchmark_format=json"]
    if cpu is not None and shutil.which("taskset"):
        cmd = ["taskset", "-c", str(cpu)] + cmd
    return cmd


def counters(cmd, out, err, code, names):
    """The named counters of the one benchmark a run's filter matched."""
    results = benchmark_json(cmd, out, err, code, "ceiling.py")
    runs = [b for b in results if b.get("run_type") != "aggregate"]
    if len(runs) != 1:
        sys.exit(f"ceiling.py: {' '.join(cmd)}: the filter matched {len(runs)} benchmarks, "
                 "expected exactly 1")
    for c in names:
        if c not in runs[0]:
            sys.exit(f"ceiling.py: {runs[0]['name']} has no counter {c!r}")
    return [float(runs[0][c]) for c in names]


def run(cmd, env, names):
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    return counters(cmd, p.stdout, p.stderr, p.returncode, names)


def run_pair(cmd_a, cmd_b, env, names):
    procs = [subprocess.Popen(c, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for c in (cmd_a, cmd_b)]
    outs = [p.communicate() for p in procs]
    return [counters(c, o, e, p.returncode, names)
            for c, (o, e), p in zip((cmd_a, cmd_b), outs, procs)]


PROBE_FILTER = "BM_LineRoundTrip|BM_ReadAfterWrite|BM_FmaShare"


def probe(machine, env):
    """Round trip (ns), read after the other core's write and after one's own (GB/s), and the
    multiply-add rate two threads get at once over one alone's (~2 a core each, ~1 one core)."""
    cmd = command(machine, PROBE_FILTER)
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    found = {}
    for b in benchmark_json(cmd, p.stdout, p.stderr, p.returncode, "ceiling.py"):
        if b.get("error_occurred"):
            sys.exit(f"ceiling.py: --probe: {b['name']}: {b.get('error_message', 'skipped')}")
        found[b["name"].split("/real_time")[0]] = b
    try:
        return (float(found["BM_LineRoundTrip"]["round_trip_ns"]),
                float(found["BM_ReadAfterWrite/other:1"]["gb_per_s"]),
                float(found["BM_ReadAfterWrite/other:0"]["gb_per_s"]),
                float(found["BM_FmaShare"]["share"]))
    except KeyError as e:
        sys.exit(f"ceiling.py: --probe: {' '.join(cmd)} gave no {e}")


def main(argv):
    a, prog, env = parse_args(argv)
    phases = [c for c in a.phases.split(",") if c]
    names = [a.counter] + phases
    alone, copies, two = [], [], []
    phase = {"1 thread alone": [], "one of two copies": [], "2 threads": []}
    placement = []
    for r in range(a.rounds):
        if a.probe:
            placement.append(probe(a.machine, env))
            print(f"round {r + 1} of {a.rounds}: round trip {placement[-1][0]:.0f} ns, read after "
                  f"the other core's write {placement[-1][1]:.1f} GB/s, after its own "
                  f"{placement[-1][2]:.1f}, multiply-add share {placement[-1][3]:.2f}",
                  file=sys.stderr)
        one = run(command(prog, a.one), env, names)
        pair = run_pair(command(prog, a.one, 0), command(prog, a.one, 1), env, names)
        both = run(command(prog, a.two), env, names)
        alone.append(one[0])
        copies.append(pair[0][0] + pair[1][0])
        two.append(both[0])
        phase["1 thread alone"].append(one[1:])
        phase["one of two copies"].append([(x + y) / 2 for x, y in zip(pair[0][1:], pair[1][1:])])
        phase["2 threads"].append(both[1:])
        print(f"round {r + 1} of {a.rounds}: alone {alone[-1]:.4g}, two copies {copies[-1]:.4g}, "
              f"2 threads {two[-1]:.4g}", file=sys.stderr)
    med = statistics.median
    print(f"{a.counter}, medians of {a.rounds} rounds: 1 thread alone {med(alone):.4g}, "
          f"two 1-thread copies at once (summed) {med(copies):.4g}, 2 threads {med(two):.4g}")
    rows = [("two copies / alone (the machine's ceiling)", [c / x for c, x in zip(copies, alone)]),
            ("2 threads / alone", [t / x for t, x in zip(two, alone)]),
            ("2 threads / two copies", [t / c for t, c in zip(two, copies)])]
    for name, v in rows:
        print(f"  {name:44s} median {med(v):.3f}   by round: " + ", ".join(f"{x:.3f}" for x in v))
    if placement:
        print("  placement by round (round trip ns, other's / own GB/s, multiply-add share): " +
              ", ".join(f"{t:.0f} {o:.0f}/{w:.0f} {s:.2f}" for t, o, w, s in placement))
    for name, v in phase.items():
        if phases:
            print(f"  {name:20s} " + "  ".join(
                f"{c} {med([x[k] for x in v]):.4g}" for k, c in enumerate(phases)))


if __name__ == "__main__":
    main(sys.argv[1:])
