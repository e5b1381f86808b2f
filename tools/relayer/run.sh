#!/usr/bin/env bash
# Runs a fixed set of oddball commands into OUT, for comparing a behaviour-preserving change:
#   tools/relayer/run.sh BIN OUT FIXTURES   (BIN: an oddball binary; FIXTURES: a folder holding
#   online.xdf, an `oddball online --model` recording, and model.json, the model it used)
# then `python3 tools/relayer/compare.py OUT_BEFORE OUT_AFTER`. Every output file must be equal
# byte for byte, JSON and stdout with their timings left out (compare.py says which).
set -uo pipefail
BIN=$(realpath "$1"); OUT=$2; FIX=$(realpath "$3")
D=${ODDBALL_DATA:-$(cd "$(dirname "$0")/../.." && pwd)/../shared/data}
E3=$D/bci2000-samplefiles-p300; IIB=$D/bci-competition-ii-iib
mkdir -p "$OUT"; OUT=$(realpath "$OUT"); cd "$(dirname "$0")/../.."
run() { # run NAME ARGS…: stdout, stderr and the exit code into OUT/NAME.* (RELAYER_SKIP="a b": not these)
  local name=$1; shift
  case " ${RELAYER_SKIP:-} " in *" $name "*) return ;; esac
  "$BIN" "$@" >"$OUT/$name.stdout" 2>"$OUT/$name.stderr"; echo $? >"$OUT/$name.rc"
}
run bench benchmark datasets/bci2000-eeg2.toml datasets/bci2000-eeg3.toml datasets/bci-competition-ii-iib.toml datasets/muse-visual-p300.toml \
  --pipeline all --protocol train-test --json "$OUT/bench.json" --csv "$OUT/bench.csv"
run eval_e3_21 evaluate --train "$E3/eeg3_2.dat" --test "$E3/eeg3_1.dat" --pipeline all --out "$OUT/eval_e3_21.json"
run eval_cv evaluate --train "$E3/eeg3_1.dat" --pipeline lda,riemann,stack --tune --out "$OUT/eval_cv.json"
run train_e3 train "$E3/eeg3_1.dat" --pipeline stack --out "$OUT/train_e3.json"
run demo demo --out "$OUT/demo"
run demo_none demo --calibration none --out "$OUT/demo_none"
run demo_adapt demo --adapt --out "$OUT/demo_adapt"
run demo_fast demo --paradigm fast --optimise-stopping --seed 2 --out "$OUT/demo_fast"
run demo_model demo --model "$FIX/model.json" --dynamic-stopping --out "$OUT/demo_model"
run demo_transfer demo --calibration none --transfer "$FIX/model.json" --commands paper-g --seed 3 --out "$OUT/demo_transfer"
run demo_replay demo --subject "replay:$E3/eeg3_2.dat" --out "$OUT/demo_replay"
run demo_iib demo --subject "replay:$IIB/AAS012R03.mat,$IIB/AAS012R04.mat" \
  --calibration "$IIB/AAS010R01.mat,$IIB/AAS010R02.mat,$IIB/AAS011R01.mat,$IIB/AAS011R02.mat" \
  --test-text HAM,PIE --paradigm fast --optimise-stopping --round-limit 5 --out "$OUT/demo_iib"
run task_track task track --targets 3 --out "$OUT/task_track"
run task_draw task draw --draw HI --dynamic-stopping --out "$OUT/task_draw"
run online_replay online --model "$FIX/model.json" --seed 3 --commands up,left,down --source "replay:$FIX/online.xdf" --fast --out "$OUT/online_replay"
run unsup evaluate --unsupervised --test "$E3/eeg3_1.dat" --test "$E3/eeg3_2.dat" --json "$OUT/unsup.json"
run inspect inspect "$E3/eeg3_1.dat" --plot "$OUT/inspect_erp.png"
