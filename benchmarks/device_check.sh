#!/usr/bin/env bash
# The accelerator check of the time-to-first-result work: one prepared call on a lent GPU machine, under 10 minutes.
#
#     bash benchmarks/device_check.sh [OUT_FOLDER]      # default: $OUT, else benchmarks/results
#
# 1. what the machine is (nvidia-smi, Python, JAX and its devices) and that geojax imports: stops here if not;
# 2. benchmarks/accelerator.py at the GPU sizes (the QFFC sweep of 131,072 x 1 yr first: the target of
#    >= 1e4 sample-years/s after compilation), step batches 16,384 and 131,072 (two of the four, for time);
# 3. benchmarks/startup.py for this tree alone (no git history on such a machine): the one-year, 30-day and
#    10-days-after-30 QFFC runs, cold (empty cache) and warm (second process).
# Each part has its own time limit (ACCELERATOR_S, STARTUP_S) and writes its results files as it goes, so a part
# cut short keeps what it measured.  Pure-Python packages the machine may lack (filelock, flatbuffers, clarabel)
# come from .device-deps/ when it is there (pip install --target .device-deps ...), after the machine's own.
set -u
out=${1:-${OUT:-benchmarks/results}}
mkdir -p "$out"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}:$PWD/.device-deps"
log="$out/device_check.log"
{
  nvidia-smi -L
  python3 -c "import sys, jax; print(sys.version.split()[0], 'jax', jax.__version__, jax.devices())"
  python3 -c "import geojax.cli, geojax.sweep; print('geojax imports')"
} > "$log" 2>&1 || { cat "$log"; exit 1; }
timeout "${ACCELERATOR_S:-330}" python3 benchmarks/accelerator.py --out "$out" --batches 16384 131072 \
  > "$out/accelerator.log" 2>&1
echo "accelerator.py: exit $?" >> "$log"
timeout "${STARTUP_S:-170}" python3 benchmarks/startup.py --baseline none --no-batch --out "$out" \
  --only 'simulate qffc 1 yr' 'simulate qffc 30 d' 'simulate qffc 10 d after 30 d' > "$out/startup.log" 2>&1
echo "startup.py: exit $?" >> "$log"
cat "$log"
tail -n 8 "$out/accelerator.log" "$out/startup.log"
