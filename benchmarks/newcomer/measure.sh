#!/usr/bin/env bash
# A newcomer's first five minutes, timed: clone, `pip install .` into a fresh venv, then the
# README's quick start (one analysis, the Python snippet with a watched simulation, one
# `gimwatch simulate`), the README's "watch your own loop" block twice (the first run compiles
# gimwatch's numba kernels into the fresh install, the second loads them) and `gimwatch demo`.
# Writes benchmarks/newcomer/times.json, with the fingerprint of the gimwatch modules these
# commands import (gimwatch.bench.freshness: tests/test_docs.py fails once that code changes).
# Usage: bash benchmarks/newcomer/measure.sh [PYTHON]   (from the repository root)
set -euo pipefail
PYTHON=${1:-python3}
ROOT=$(pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
unset PYTHONPATH NUMBA_CACHE_DIR
now() { date +%s.%N; }
since() { printf "%.2f" "$(echo "$(now) - $1" | bc)"; }

git clone --quiet "$ROOT" "$WORK/gimwatch"
cd "$WORK/gimwatch"
t=$(now); "$PYTHON" -m venv "$WORK/venv"; "$WORK/venv/bin/pip" install --quiet . 2>/dev/null
install_s=$(since "$t")
cd "$WORK"   # the quick start runs from any directory
t=$(now); "$WORK/venv/bin/gimwatch" analyze ur5 > analyze.txt; analyze_s=$(since "$t")
# the README's watch-your-own-loop block (its second python block), first and second run
awk '/^```python/{n++; if (n == 2) {on = 1; next}} /^```$/{on = 0} on' \
  "$WORK/gimwatch/README.md" > watch_loop.py
t=$(now); "$WORK/venv/bin/python" watch_loop.py > watch1.txt 2>&1; watch_first_s=$(since "$t")
t=$(now); "$WORK/venv/bin/python" watch_loop.py > watch2.txt 2>&1; watch_cached_s=$(since "$t")
# the quick start's Python block (the first one in the README)
awk '/^```python/{n++; if (n == 1) {on = 1; next}} /^```$/{on = 0} on' \
  "$WORK/gimwatch/README.md" > quickstart.py
t=$(now); "$WORK/venv/bin/python" quickstart.py > quickstart.txt; python_s=$(since "$t")
t=$(now); "$WORK/venv/bin/gimwatch" simulate chain_10 -o run \
  > simulate.txt 2>/dev/null; simulate_s=$(since "$t")
t=$(now); "$WORK/venv/bin/gimwatch" demo -o demo-output > /dev/null 2>&1; demo_s=$(since "$t")
"$WORK/venv/bin/python" - > measured_code.json <<'PY'
import json
from pathlib import Path

from gimwatch.bench.freshness import fingerprint, modules_imported_by

cases = [
    ["-m", "gimwatch", "analyze", "ur5"],
    ["-c", Path("watch_loop.py").read_text()],
    ["-c", Path("quickstart.py").read_text()],
    ["-m", "gimwatch", "simulate", "chain_10", "-o", "probe-run"],
    ["-m", "gimwatch", "demo", "--duration", "0.05", "-o", "probe-demo"],
]
print(json.dumps(fingerprint(modules_imported_by(cases, Path.cwd())), indent=2))
PY
cat > "$ROOT/benchmarks/newcomer/times.json" <<JSON
{
  "date": "$(date -u '+%Y-%m-%d %H:%M UTC')",
  "commit": "$(git -C "$WORK/gimwatch" rev-parse --short HEAD)",
  "python": "$("$PYTHON" --version 2>&1)",
  "cpus": $(nproc),
  "note": "pip's download cache as found on the machine",
  "pip_install_s": $install_s,
  "analyze_ur5_s": $analyze_s,
  "readme_python_snippet_s": $python_s,
  "readme_watch_loop_first_run_s": $watch_first_s,
  "readme_watch_loop_second_run_s": $watch_cached_s,
  "simulate_chain_10_s": $simulate_s,
  "demo_s": $demo_s,
  "install_analysis_and_simulation_s": $(printf "%.2f" "$(echo "$install_s + $analyze_s + $python_s + $simulate_s" | bc)"),
  "measured_code": $(cat measured_code.json)
}
JSON
cat "$ROOT/benchmarks/newcomer/times.json"
