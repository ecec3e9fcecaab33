#!/usr/bin/env bash
# A newcomer's first five minutes, timed: clone, `pip install .` into a fresh venv, then the
# README's quick start (one analysis, the Python snippet with a watched simulation, one
# `gimwatch simulate`) and `gimwatch demo`. Writes benchmarks/newcomer/times.json.
# Usage: bash benchmarks/newcomer/measure.sh [PYTHON]   (from the repository root)
set -euo pipefail
PYTHON=${1:-python3}
ROOT=$(pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
unset PYTHONPATH
now() { date +%s.%N; }
since() { printf "%.2f" "$(echo "$(now) - $1" | bc)"; }

git clone --quiet "$ROOT" "$WORK/gimwatch"
cd "$WORK/gimwatch"
t=$(now); "$PYTHON" -m venv "$WORK/venv"; "$WORK/venv/bin/pip" install --quiet . 2>/dev/null
install_s=$(since "$t")
cd "$WORK"   # the quick start runs from any directory
t=$(now); "$WORK/venv/bin/gimwatch" analyze ur5 > analyze.txt; analyze_s=$(since "$t")
# the quick start's Python block (the first one in the README)
awk '/^```python/{n++; if (n == 1) {on = 1; next}} /^```$/{on = 0} on' \
  "$WORK/gimwatch/README.md" > quickstart.py
t=$(now); "$WORK/venv/bin/python" quickstart.py > quickstart.txt; python_s=$(since "$t")
t=$(now); "$WORK/venv/bin/gimwatch" simulate chain_10 -o run \
  > simulate.txt 2>/dev/null; simulate_s=$(since "$t")
t=$(now); "$WORK/venv/bin/gimwatch" demo -o demo-output > /dev/null 2>&1; demo_s=$(since "$t")
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
  "simulate_chain_10_s": $simulate_s,
  "demo_s": $demo_s,
  "install_analysis_and_simulation_s": $(printf "%.2f" "$(echo "$install_s + $analyze_s + $python_s + $simulate_s" | bc)")
}
JSON
cat "$ROOT/benchmarks/newcomer/times.json"
