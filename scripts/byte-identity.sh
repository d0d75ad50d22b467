#!/usr/bin/env bash
# Byte identity of every example's outputs, for refactors that must not change behaviour.
#
#   scripts/byte-identity.sh OSLF_BINARY OUT_DIR     # bake, render and trace into OUT_DIR,
#                                                    # then write OUT_DIR/SHA256SUMS
#   scripts/byte-identity.sh --compare DIR_A DIR_B [OSLF_BINARY]
#                                                    # list the files whose bytes differ (with
#                                                    # a binary: `oslf compare` of each EXR)
#
# Covers: the CPU bake of each example (rgb9e5, and bc6h for the gazebo and the room), a small
# GPU bake of each example on the default adapter (lavapipe here), every runtime mode of each
# store (the GPU shader and, for the gazebo and the room, the CPU reference), the environment
# baselines, and the truth of every mode. Settings are small so that a run takes minutes on
# two cores; the outputs are as deterministic as the product (same bytes on the same device).
set -euo pipefail

if [[ "${1:-}" == "--compare" ]]; then
    a=$2 b=$3
    if diff <(cd "$a" && sort -k2 SHA256SUMS) <(cd "$b" && sort -k2 SHA256SUMS) >/dev/null; then
        echo "byte-identical: $(wc -l <"$a/SHA256SUMS") files"
        exit 0
    fi
    echo "differ:"
    join -j2 <(sort -k2 "$a/SHA256SUMS") <(sort -k2 "$b/SHA256SUMS") | awk '$2 != $3 {print $1}' |
        while read -r f; do
            if [[ -n "${4:-}" && "$f" == *.exr ]]; then
                echo "  $f: $("$4" compare --mask all "$a/$f" "$b/$f" | tr '\n' ' ')"
            else
                echo "  $f"
            fi
        done
    exit 1
fi

bin=$(realpath "$1")
out=$2
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
out=$(realpath "$out")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$root/examples/." "$work/"
# A small preset for the GPU bake, appended to copies of the scenes.
for s in gazebo meshes orb room; do
    printf '\n[presets.identity-gpu]\nsample_count = 40\ncube_resolution = 16\nsamples_per_texel = 4\n' >>"$work/$s.toml"
done

run() { echo "+ oslf $*" >&2; "$bin" "$@"; }
size=(--width 160 --height 112)
modes=(recon mirror recon-mirror glossy recon-glossy pbr)

for s in gazebo meshes orb room; do
    run bake "$work/$s.toml" -o "$out/$s.oslf" --device cpu --preview none -q
    run bake "$work/$s.toml" -o "$out/$s-gpu.oslf" --device gpu --preset identity-gpu --preview none -q
    for m in "${modes[@]}"; do
        run render "$out/$s.oslf" --mode "$m" "${size[@]}" -o "$out/$s-$m.exr"
    done
    run render "$out/$s-gpu.oslf" --mode recon-glossy "${size[@]}" -o "$out/$s-gpu-recon-glossy.exr"
    run render "$out/$s.oslf" --mode pbr --source env "${size[@]}" -o "$out/$s-pbr-env.exr"
    run render "$out/$s.oslf" --mode pbr --source parallax --glossy-filter split-sum "${size[@]}" -o "$out/$s-pbr-parallax-splitsum.exr"
    run truth "$work/$s.toml" --modes recon,mirror,recon-mirror,glossy,recon-glossy,pbr --spp 8 "${size[@]}" -o "$out/$s-truth" -q
done
for s in gazebo room; do
    run bake "$work/$s.toml" -o "$out/$s-bc6h.oslf" --encoding bc6h --device cpu --preview none -q
    run render "$out/$s-bc6h.oslf" --mode recon-glossy "${size[@]}" -o "$out/$s-bc6h-recon-glossy.exr"
    for m in recon-mirror glossy pbr; do
        run render "$out/$s.oslf" --mode "$m" --cpu "${size[@]}" -o "$out/$s-$m-cpu.exr"
    done
done
(cd "$out" && sha256sum -- *.oslf *.exr *.png >SHA256SUMS)
echo "wrote $out/SHA256SUMS ($(wc -l <"$out/SHA256SUMS") files)"
