#!/usr/bin/env bash
# The tensile job's film validation runs (docs/tensile.md, "Validation"): tensile.md §5 Level 1's
# "modulus convergence with size", reduced to what one core does in about an hour.
#
#   bench/validate_tensile_films.sh VALIDATE OUTDIR [SIDES] [SEEDS] [RELAX_PS]
#
# VALIDATE is the validate_tensile binary (bench/validate_tensile.cpp: `film` runs one tensile job
# in-process, the engine's own TensileJob as `mdem run tensile` builds it, and prints its summary
# and wall time); OUTDIR gets one report per run (<name>.txt) and runs.tsv (name, side, seed,
# case, wall seconds, exit code). Defaults: SIDES "100 150",
# SEEDS "1 2 3", RELAX_PS 1000. Films keep Table 5-1's small film's areal segment density
# (40 000 segments on 300 × 300 nm: 0.444 /nm²), tube length 0.95 × side and 11 nm thickness.
# Cases per side and seed (CASES, default all four, in this order; "none": none):
#   relaxed    relax RELAX_PS, then 2 % tensile at the thesis rate (1e-4 /ps, 600 ps ramp)
#   ready      no relaxation (ready-to-relax, Table 5-3), the same test
#   nps        as relaxed, with NPs at the small film's largest NP density (2000 on 300 × 300 nm),
#              deposited after the relaxation (the thesis's order, L797)
#   ready_nps  as ready, with the same NPs deposited into the pre-relaxed film
# then one cyclic run on the first side (CYCLIC_SEED, default the first seed; "none": no cyclic
# run): relax CYCLIC_RELAX_PS (default RELAX_PS), then CYCLIC_CYCLES (6) cycles to -1 % at
# Table 5-5's 5.7e-5 /ps mean rate. Runs on one thread (OMP_NUM_THREADS=1, --threads 1), niced,
# one after another; a run whose report already exists is skipped, so the script resumes.
# bench/validate_tensile_table.py OUTDIR prints the tables.
set -u
validate=${1:?usage: $0 VALIDATE OUTDIR [SIDES] [SEEDS] [RELAX_PS]}
out=${2:?usage: $0 VALIDATE OUTDIR [SIDES] [SEEDS] [RELAX_PS]}
sides=${3:-100 150}
seeds=${4:-1 2 3}
relax=${5:-1000}
cases=${CASES:-relaxed ready nps ready_nps}
cyclic_seed=${CYCLIC_SEED:-${seeds%% *}}
cyclic_cycles=${CYCLIC_CYCLES:-6}
cyclic_relax=${CYCLIC_RELAX_PS:-$relax}
mkdir -p "$out"
export OMP_NUM_THREADS=1

segment=1.356                # nm, the (10,10) segment length
density=$(python3 -c 'print(40000 / 300.0**2)')
np_density=$(python3 -c 'print(2000 / 300.0**2)')

film_flags() {  # side -> --side --tubes --segments
  python3 - "$1" "$segment" "$density" <<'EOF'
import sys
side, seg, dens = map(float, sys.argv[1:4])
n_seg = round(0.95 * side / seg)
tubes = round(dens * side * side / n_seg)
print(f"--side {side:g} --tubes {tubes} --segments {int(n_seg)}")
EOF
}

run() {  # name, then validate_tensile film options
  local name=$1
  shift
  if [[ -s "$out/$name.txt" ]]; then
    echo "skip $name (done)"
    return
  fi
  echo "run  $name: $*"
  local t0 t1 rc
  t0=$(date +%s.%N)
  nice -n 5 "$validate" film "$@" --threads 1 >"$out/$name.tmp" 2>"$out/$name.err"
  rc=$?
  t1=$(date +%s.%N)
  mv "$out/$name.tmp" "$out/$name.txt"
  local wall
  wall=$(python3 -c "print(f'{$t1 - $t0:.1f}')")
  echo "     $name: exit $rc, $wall s"
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$side" "$seed" "$case" "$wall" "$rc" >>"$out/runs.tsv"
}

# 2 % at the thesis's rate (1e-7/fs) after its 0.6 ns ramp.
test_flags=(--target 0.02 --rate 1e-4 --ramp 600 --report-strains 0,0.02)
for side in $sides; do
  flags=$(film_flags "$side")
  nps=$(python3 -c "print(round($np_density * $side * $side))")
  # Seed by seed, so that a budget cut leaves whole seeds (each gives its ratios).
  for seed in $seeds; do
    for case in $cases; do
      case $case in
        relaxed)
          run "s${side}_seed${seed}_relaxed" $flags --seed "$seed" --relax-ps "$relax" \
            --report-times 0,"$relax" "${test_flags[@]}" ;;
        nps)
          run "s${side}_seed${seed}_nps${nps}" $flags --seed "$seed" --relax-ps "$relax" \
            --nps "$nps" --report-times 0,"$relax" "${test_flags[@]}" ;;
        ready)
          run "s${side}_seed${seed}_ready" $flags --seed "$seed" --relax-ps 0 "${test_flags[@]}" ;;
        ready_nps)
          run "s${side}_seed${seed}_ready_nps${nps}" $flags --seed "$seed" --relax-ps 0 \
            --nps "$nps" "${test_flags[@]}" ;;
        none) ;;
        *) echo "unknown case $case" >&2; exit 2 ;;
      esac
    done
  done
done
if [[ $cyclic_seed != none ]]; then
  side=${sides%% *}
  seed=$cyclic_seed
  case=cyclic
  flags=$(film_flags "$side")
  run "s${side}_seed${seed}_cyclic${cyclic_cycles}_relax${cyclic_relax}" $flags --seed "$seed" \
    --relax-ps "$cyclic_relax" --report-times 0,"$cyclic_relax" --cycles "$cyclic_cycles" \
    --amplitude 0.01 --cyclic-rate 5.7e-5
fi
