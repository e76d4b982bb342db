#!/usr/bin/env bash
# CI test of the Slurm deployment on a real single-node Slurm started here (local-slurm.sh):
# submit.sh splits a Cornell box render into 3 parts, the second part fails on its first attempt
# (a wrapper around the binary) and Slurm runs it again, the merge job combines the parts, and
# the merged image must equal the single render within float rounding. Then it measures the
# speed-up of 2 parts over 1 on this machine's cores (printed, not asserted).
#
#   deploy/slurm/test.sh [NEUMANN]     (default: target/release/neumann, built if missing)
#   BENCH_FLAGS="--res 384x384 --spp 128" deploy/slurm/test.sh    (a larger speed-up measurement)
#
# Needs root (it starts munged, slurmctld and slurmd) and stops the daemons it started.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/target/release/neumann}
[ -x "$bin" ] || (cd "$root" && cargo build --release --quiet)
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin") # the jobs run in other folders
work=$(mktemp -d /tmp/neumann-slurm-test.XXXXXX)
"$root/deploy/slurm/local-slurm.sh" start >/dev/null
trap '"$root/deploy/slurm/local-slurm.sh" stop; rm -rf "$work"' EXIT

# Waits for job $1 to end, releasing requeued tasks that Slurm holds for two minutes (a test
# need not wait for that); prints its final state.
wait_for() {
    for _ in $(seq 600); do
        squeue -h -t PD -r -o '%i %r' | awk '$2 == "BeginTime" { print $1 }' |
            while read -r id; do scontrol update JobId="$id" StartTime=now 2>/dev/null || true; done
        state=$(scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
        case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) echo "$state"; return ;; esac
        sleep 0.5
    done
    echo "TIMEOUT-WAITING"
}

# A binary that fails the first attempt of part 2/3.
cat > "$work/flaky" <<WRAP
#!/bin/sh
case "\$*" in *"--part 2/3"*)
    if [ ! -f "$work/failed-once" ]; then touch "$work/failed-once"; echo "injected failure" >&2; exit 1; fi ;;
esac
exec "$bin" "\$@"
WRAP
chmod +x "$work/flaky"

flags="--res 48x32 --spp 24 --seed 11"
read -r array merge < <(cd "$work" && NEUMANN="$work/flaky" "$root/deploy/slurm/submit.sh" cbox 3 merged.exr $flags)
state=$(wait_for "$merge")
echo "array job $array, merge job $merge: $state"
for f in "$work"/merged-parts/*.log; do echo "--- $(basename "$f")"; cat "$f"; done
[ "$state" = COMPLETED ] || { echo "FAIL: the merge job ended $state" >&2; exit 1; }
grep -q "asking Slurm to run it again" "$work/merged-parts/part-2.log" || { echo "FAIL: part 2 was not retried" >&2; exit 1; }
grep -q "attempt 2" "$work/merged-parts/part-2.log" || { echo "FAIL: part 2 did not run again" >&2; exit 1; }

# The merged image equals the single render within float rounding.
"$bin" render cbox $flags --quiet -o "$work/single.pfm" >/dev/null
"$bin" merge "$work/merged.exr" -o "$work/merged.pfm" >/dev/null
python3 - "$work/merged.pfm" "$work/single.pfm" <<'PY'
import struct, sys
def pfm(path):
    data = open(path, 'rb').read()
    head = data.split(b'\n', 3)
    return struct.unpack('<%df' % ((len(head[3])) // 4), head[3])
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
assert len(a) == len(b) > 0, (len(a), len(b))
worst = max(abs(x - y) / max(abs(y), 1e-30) for x, y in zip(a, b))
same = sum(x == y for x, y in zip(a, b)) / len(a)
print(f"merged vs single render: largest relative difference {worst:.2e}, {same:.0%} of values bit-identical")
assert worst < 2 ** -20, worst
PY

# A part that keeps failing: the merge job fails and names it.
cat > "$work/broken" <<WRAP
#!/bin/sh
case "\$*" in *"--part 1/2"*) exit 1 ;; esac
exec "$bin" "\$@"
WRAP
chmod +x "$work/broken"
read -r _ merge < <(cd "$work" && NEUMANN="$work/broken" "$root/deploy/slurm/submit.sh" cbox 2 broken.exr $flags)
state=$(wait_for "$merge")
[ "$state" = FAILED ] || { echo "FAIL: a merge with a missing part ended $state" >&2; exit 1; }
grep -q "missing: samples 0–12 of every pixel (part 1/2)" "$work/broken-parts/merge.log" ||
    { echo "FAIL: the merge did not name the missing part" >&2; cat "$work/broken-parts/merge.log"; exit 1; }
echo "a part failing on every attempt: the merge job fails naming it"

# Speed-up of N parts over one on this machine (one core per part). Small in CI, where Slurm's
# few seconds of overhead per submission weigh; the README's figures come from
# BENCH_FLAGS="--res 384x384 --spp 128 --seed 3" deploy/slurm/test.sh.
cpus=$(nproc)
bench=${BENCH_FLAGS:---res 256x256 --spp 64 --seed 3}
elapsed() {
    local t0 t1 merge
    t0=$(date +%s.%N)
    read -r _ merge < <(cd "$work" && NEUMANN="$bin" "$root/deploy/slurm/submit.sh" cbox "$1" "bench$1.exr" $bench)
    [ "$(wait_for "$merge")" = COMPLETED ] || { echo "FAIL: benchmark with $1 parts" >&2; exit 1; }
    t1=$(date +%s.%N)
    echo "$t1 - $t0" | bc -l
}
one=$(elapsed 1)
many=$(elapsed "$cpus")
printf 'speed-up on %d cores: 1 part %.2f s, %d parts %.2f s (submission to merged image): %.2fx\n' \
    "$cpus" "$one" "$cpus" "$many" "$(echo "$one / $many" | bc -l)"
echo "slurm test passed"
