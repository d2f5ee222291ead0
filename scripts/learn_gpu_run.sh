#!/bin/bash
# One call on a GPU machine without mmusv installed (torch + numpy only): train the models (MODES; by default
# single, early and intermediate) side by side on the one GPU (a process each, T seconds each, the loader workers
# split between them), then run them on the test cache side by side, and leave under $OUT what comes back
# from such a call: run.log (every process's output, prefixed, and the GPU's load every 15 s), fp16 copies of
# the models (<mode>_model_fp16.pt, under the 16 MiB file limit), their loss logs (<mode>_log.jsonl) and the
# heatmap peaks of all of them (peaks.npz, for `python -m mmusv.learn.replay` back on a machine with mmusv).
# A training process that dies or hangs does not stop the rest: each writes model.pt at every epoch end and at
# the time limit, the script goes on with the models that exist, and every step has a timeout so that the call
# ends inside about T + 180 s.
#
# Run from the repository root, with C a folder holding train.npz and test.npz (`mmusv train --cache-only`):
#   C=.learncache/gpu3 T=360 OUT=$OUT bash scripts/learn_gpu_run.sh
# Knobs (environment): MODES (the models, space-separated; default "single early intermediate"), PRESET
# (paper), SETS (preset overrides, space-separated KEY=VALUE, passed as --set), WORKERS (loader workers, one number
# per mode), THREADS (torch threads per process), DEVICE (cuda when available), INFER_LIMIT (first N items per
# model: dry runs), INFER_TIMEOUT (s), W (where models are written).
set -u
export PYTHONUNBUFFERED=1
C=${C:-.learncache/gpu3}
T=${T:-360}
PRESET=${PRESET:-paper}
SETS=${SETS-"min_points=1 code_weights=[1,1,0.1,1,1,1,1,1]"}
WORKERS=${WORKERS:-"3 6 4"}
THREADS=${THREADS:-1}
DEVICE=${DEVICE:-}
INFER_LIMIT=${INFER_LIMIT:-}
INFER_TIMEOUT=${INFER_TIMEOUT:-100}
OUT=${OUT:-/tmp/out}
W=${W:-/tmp/models}
read -ra MODES <<<"${MODES:-single early intermediate}"
read -ra sets <<<"$SETS"
read -ra workers <<<"$WORKERS"
set_args=()
for s in "${sets[@]}"; do set_args+=(--set "$s"); done
dev_args=()
[ -n "$DEVICE" ] && dev_args=(--device "$DEVICE")
lim_args=()
[ -n "$INFER_LIMIT" ] && lim_args=(--limit "$INFER_LIMIT")
mkdir -p "$W" "$OUT"
LOG=$OUT/run.log
t0=$(date +%s)
say() { echo "[run] $(($(date +%s) - t0)) s: $*" | tee -a "$LOG"; }
say "preset $PRESET, sets ${SETS:-none}, T $T s, workers $WORKERS, cache $C"
if command -v nvidia-smi >/dev/null; then
  nvidia-smi -L 2>&1 | tee -a "$LOG"
  nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader -l 15 2>&1 | sed -u 's/^/[gpu] /' >>"$LOG" &
  mon=$!
else
  mon=
fi
python3 -c "import torch, numpy; print('torch', torch.__version__, 'numpy', numpy.__version__, 'cuda', torch.cuda.is_available())" 2>&1 | tee -a "$LOG"

pids=()
for i in "${!MODES[@]}"; do
  m=${MODES[$i]}
  timeout -k 10 $((T + 45)) python3 scripts/learn_train.py --cache "$C/train.npz" --preset "$PRESET" "${set_args[@]}" \
    --modes "$m" -o "$W" --time-limit "$T" --workers "${workers[$i]}" --threads "$THREADS" --no-progress "${dev_args[@]}" \
    2>&1 | sed -u "s/^/[$m] /" >>"$LOG" &
  pids+=($!)
done
for p in "${pids[@]}"; do wait "$p"; done
say "training done"

# fp16 copies and logs first, so that they come back even if inference fails
W=$W OUT=$OUT MODES="${MODES[*]}" python3 - <<'PY' 2>&1 | sed -u 's/^/[copy] /' | tee -a "$LOG"
import os, shutil, torch
W, OUT = os.environ["W"], os.environ["OUT"]
for m in os.environ["MODES"].split():
    f = os.path.join(W, m, "model.pt")
    if not os.path.isfile(f):
        print(m, "no model.pt")
        continue
    ck = torch.load(f, map_location="cpu", weights_only=True)
    ck["model"] = {k: (v.half() if v.is_floating_point() else v) for k, v in ck["model"].items()}
    ck["fp16_copy"] = True
    torch.save(ck, os.path.join(OUT, f"{m}_model_fp16.pt"))
    shutil.copy(os.path.join(W, m, "log.jsonl"), os.path.join(OUT, f"{m}_log.jsonl"))
    print(m, "epoch", ck["epoch"], "step", ck["step"], "seconds", round(ck["seconds"], 1),
          "steps/s", round(ck["step"] / max(ck["seconds"], 1e-9), 2))
PY
say "copies done"

pids=()
parts=()
for m in "${MODES[@]}"; do
  [ -f "$W/$m/model.pt" ] || continue
  timeout -k 5 "$INFER_TIMEOUT" python3 scripts/learn_train.py infer --cache "$C/test.npz" --models "$W" --modes "$m" \
    -o "/tmp/peaks_$m.npz" "${dev_args[@]}" "${lim_args[@]}" 2>&1 | sed -u "s/^/[infer $m] /" >>"$LOG" &
  pids+=($!)
  parts+=("/tmp/peaks_$m.npz")
done
for p in "${pids[@]}"; do wait "$p"; done
say "inference done"
if [ ${#parts[@]} -gt 0 ]; then
  python3 scripts/learn_train.py merge -o "$OUT/peaks.npz" "${parts[@]}" 2>&1 | sed -u 's/^/[merge] /' | tee -a "$LOG"
fi
[ -n "$mon" ] && kill "$mon" 2>/dev/null
say "end"
ls -la "$OUT" | tee -a "$LOG"
