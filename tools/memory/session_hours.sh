#!/usr/bin/env bash
# Peak RSS of long sessions (issue #30): online over the simulated subject unpaced (--fast), 10
# minutes against 8 hours of session at the paper's timing (10.36 s a decision), calibrated,
# adapted and uncalibrated; demo at 100 and 1,000 decisions. Usage: session_hours.sh BIN OUT
set -euo pipefail
bin=${1:?oddball binary}; out=${2:?output folder}
mkdir -p "$out"
run() { # name n_decisions args...
  local name=$1 n=$2; shift 2
  local cmds; cmds=$(python3 -c "print(','.join(['u','d']*($n//2)))")
  /usr/bin/time -f "%M" -o "$out/$name.rss" "$bin" "$@" --commands "$cmds" --out "$out/$name" \
    > "$out/$name.log" 2>&1
  echo "$name decisions=$n peak_rss_kb=$(tail -1 "$out/$name.rss")"
}
run demo100 100 demo
run demo1000 1000 demo
run online10min 58 online --calibrate --fast
run online8h 2770 online --calibrate --fast
run online10min-adapt 58 online --calibrate --adapt --fast
run online8h-adapt 2770 online --calibrate --adapt --fast
run online10min-none 58 online --calibration none --fast
run online8h-none 2770 online --calibration none --fast
