#!/usr/bin/env bash
# Runs every benchmark, one after another (they share the cores, so never in parallel), and
# keeps their output in benchmarks/out/<date>/. As root (emulation), after scripts/setup.sh.
#   bash benchmarks/run.sh            all, about 30-40 min on 2 cores
#   bash benchmarks/run.sh --quick    smaller sizes, about 10 min
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
out="benchmarks/out/$(date -u +%Y%m%dT%H%M%SZ)"
mkdir -p "$out"
quick=0; [[ "${1:-}" == "--quick" ]] && quick=1
run() { echo "== $*" | tee -a "$out/log.txt"; "$@" 2>&1 | tee -a "$out/log.txt"; }
if ((quick)); then
  run $PY benchmarks/flows_throughput.py --packets 200000 --flows 20000
  run $PY benchmarks/emulation_bench.py --quick --json "$out/emulation.json"
  run $PY benchmarks/run_families.py --uavs 10 --windows 3 --out "$out/runs" --json "$out/families.json"
  run $PY benchmarks/fidelity_bench.py --cases 20-ddos --json "$out/fidelity.json"
  run $PY benchmarks/ids_bench.py --runs 200 --epochs 5
else
  run $PY benchmarks/flows_throughput.py
  run $PY benchmarks/emulation_bench.py --json "$out/emulation.json"
  run $PY benchmarks/run_families.py --out "$out/runs" --json "$out/families.json"
  run $PY benchmarks/fidelity_bench.py --json "$out/fidelity.json"
  run $PY benchmarks/ids_bench.py
fi
rm -rf "$out/runs"  # pcaps of the family runs: about 1 GB per 20-UAV minute
echo "results in $out"
