#!/usr/bin/env bash
# Runs the benchmarks, one after another (they share the cores, so never in parallel), and keeps
# their output in benchmarks/out/<date>/. As root (emulation), after scripts/setup.sh with the
# bench extra (UAVCAS_EXTRAS=test,dl,bench: nfstream, dpkt).
#   bash benchmarks/run.sh            all, about 40-50 min on 2 cores
#   bash benchmarks/run.sh --quick    smaller sizes, about 15 min
# Every script in benchmarks/ is either run below or named here with the reason it is not
# (tests/test_repository.py checks that each one is named in this file):
#   torch_devices.py   needs a CUDA GPU (the CPU-vs-GPU fit times of the deep baselines; the
#                      figures in docs/results.md came from an H200): run it on such a machine
#                      with a dataset, `benchmarks/torch_devices.py DATASET --json F`.
#   medium_results.py  not a measurement: it writes docs/results.md from the medium campaign's
#                      datasets and `bench ids` outputs (hours of emulation and fits; the page's
#                      "Regenerate" section has the commands).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
out="benchmarks/out/$(date -u +%Y%m%dT%H%M%SZ)"
mkdir -p "$out"
quick=0; [[ "${1:-}" == "--quick" ]] && quick=1
run() { echo "== $*" | tee -a "$out/log.txt"; "$@" 2>&1 | tee -a "$out/log.txt"; }
# run_families.py names each run <family>-<pathloss>-<mission>-<tx dBm> (defaults: logdist, random, 30)
ddos="$out/runs/ddos-logdist-random-30"
if ((quick)); then
  run $PY benchmarks/flows_throughput.py --packets 200000 --flows 20000
  run $PY benchmarks/emulation_bench.py --quick --json "$out/emulation.json"
  run $PY benchmarks/run_families.py --uavs 10 --windows 3 --out "$out/runs" --json "$out/families.json"
  run $PY benchmarks/fidelity_bench.py --cases 20-ddos --json "$out/fidelity.json"
  run $PY benchmarks/kill_clean_cycles.py --cycles 2
  run $PY benchmarks/ids_bench.py --runs 200 --epochs 5
  run $PY benchmarks/ids_cross_dataset.py --epochs 5 --out "$out/cross_dataset.csv"
  run $PY benchmarks/routing_quality.py --seeds 1
  run $PY benchmarks/sizing.py --sizes 5,10,20 --out "$out/sizing-runs" --json "$out/sizing.json"
else
  run $PY benchmarks/flows_throughput.py
  run $PY benchmarks/emulation_bench.py --json "$out/emulation.json"
  run $PY benchmarks/run_families.py --out "$out/runs" --json "$out/families.json"
  run $PY benchmarks/fidelity_bench.py --json "$out/fidelity.json"
  run $PY benchmarks/kill_clean_cycles.py --cycles 5
  run $PY benchmarks/ids_bench.py
  run $PY benchmarks/ids_cross_dataset.py --out "$out/cross_dataset.csv"
  run $PY benchmarks/routing_quality.py
  run $PY benchmarks/sizing.py --out "$out/sizing-runs" --json "$out/sizing.json"
fi
# The family runs' DDoS run, read back: SYN rates on the wire, and its flows against the most any
# rule could label (on its extracted 5-tuple dataset).
run $PY benchmarks/flood_fidelity.py "$ddos" --json "$out/flood_fidelity.json"
run .venv/bin/uavcas extract "$ddos" --out "$out/ddos-dataset"
run $PY benchmarks/attack_flow_bound.py "$ddos" "$out/ddos-dataset"
rm -rf "$out/runs" "$out/ddos-dataset" "$out/sizing-runs"  # pcaps of the family runs: about 1 GB per 20-UAV minute
echo "results in $out"
