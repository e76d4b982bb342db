#!/usr/bin/env bash
# Fuzzes each loader for SECONDS seconds (default 20) on the nightly toolchain with cargo-fuzz,
# starting from the seed corpora (scenes/, their assets) and keeping what it finds in
# fuzz/corpus/<target> (not committed). Usage: fuzz/run.sh [SECONDS] [TARGET ...]
# An input that runs longer than 60 s counts as a hang (a failure); the limit leaves room for a
# slower machine than the ones where every input of the corpora took under a second or two.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-20}
shift || true
targets=${*:-xml render obj ply image vol nanovdb tensor part gltf pbrt render_pbrt}
mkdir -p fuzz/corpus
for t in $targets; do
    mkdir -p "fuzz/corpus/$t"
    case $t in
        xml|render) cp -n scenes/*.xml "fuzz/corpus/$t/" ;;
        obj) cp -n scenes/assets/*.obj "fuzz/corpus/$t/" ;;
        ply) cp -n scenes/assets/*.ply "fuzz/corpus/$t/" ;;
        vol) cp -n scenes/assets/*.vol "fuzz/corpus/$t/" ;;
        nanovdb) cp -n scenes/assets/*.nvdb tests/data/nanovdb/*.nvdb "fuzz/corpus/$t/"
                 # A small grid uncompressed (codec NONE): the tree itself for the fuzzer to mutate.
                 [ -e "fuzz/corpus/$t/voxels-raw.nvdb" ] || python3 tools/nanovdb/uncompress.py tests/data/nanovdb/voxels.nvdb "fuzz/corpus/$t/voxels-raw.nvdb" ;;
        tensor) cp -n scenes/assets/*.bsdf "fuzz/corpus/$t/" ;;
        gltf) cp -n scenes/*.gltf "fuzz/corpus/$t/" ;;
        pbrt|render_pbrt) cp -n scenes/*.pbrt "fuzz/corpus/$t/" ;;
        part) # Parts of a split render of the built-in scene (needs the release build).
              bin=target/release/neumann
              [ -x "$bin" ] || cargo build --release --quiet
              [ -e "fuzz/corpus/$t/part.exr" ] || "$bin" render --res 8x6 --spp 4 --part 1/2 --quiet -o "fuzz/corpus/$t/part.exr" >/dev/null
              [ -e "fuzz/corpus/$t/tile.exr" ] || "$bin" render --res 8x6 --spp 2 --pixel-bounds 2,5,1,4 --quiet -o "fuzz/corpus/$t/tile.exr" >/dev/null ;;
        image) for f in scenes/assets/*.png; do [ -e "fuzz/corpus/$t/png-$(basename "$f")" ] || { printf '\x00' | cat - "$f" > "fuzz/corpus/$t/png-$(basename "$f")"; }; done
               for f in scenes/assets/*.exr; do [ -e "fuzz/corpus/$t/exr-$(basename "$f")" ] || { printf '\x01' | cat - "$f" > "fuzz/corpus/$t/exr-$(basename "$f")"; }; done ;;
    esac
    dict=()
    case $t in
        xml|render) dict=(-dict=fuzz/xml.dict) ;;
        pbrt|render_pbrt) dict=(-dict=fuzz/pbrt.dict) ;;
    esac
    echo "fuzzing $t for $secs s"
    log=$(mktemp)
    if cargo +nightly fuzz run --fuzz-dir fuzz "$t" "fuzz/corpus/$t" -- -max_total_time="$secs" -seed=1 -rss_limit_mb=4096 -timeout=60 "${dict[@]}" >"$log" 2>&1; then
        tail -4 "$log"
        rm -f "$log"
    else
        # What failed, and the input that did it (libFuzzer prints small inputs in Base64, and
        # cargo-fuzz names the artifact): everything but the progress lines.
        echo "fuzzing $t failed:"
        grep -v -E '^#[0-9]+' "$log" | tail -120
        rm -f "$log"
        exit 1
    fi
done
