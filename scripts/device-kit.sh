#!/usr/bin/env bash
# The speed figures the open issues ask of a hardware GPU, in one command of a lent machine
# (docs/measuring.md, "On a lent GPU"). It cannot build there (no registry), so:
#
#   bash scripts/device-kit.sh pack          # here: release binaries, stripped and compressed,
#                                            # and Vulkan's loader, into .device-kit/ (ignored)
#   bash scripts/device-kit.sh run           # there, from the repository root, with .device-kit
#                                            # carried; writes into $OUT (else ./device-out)
#   bash scripts/device-kit.sh run --quick   # the same chain at toy sizes, bakes on the CPU
#                                            # but the thesis preset's first cubes: tries the kit here
#
# `run` takes about seven minutes on an NVIDIA H200, the most urgent figures first, each step
# under a timeout; a step that fails is logged and the next one runs. Its summary.md holds:
#   - the GPU bake of every example preset: rays, Mrays/s, capture and wall seconds (issue 45:
#     ≥ 1 000 Mrays/s everywhere, the gazebo's thesis preset under 8 s; issue 43: the room's
#     default bake under 10 s);
#   - the Bevy plugin's cost in the room example at 1920 × 1080, without and with a prepass
#     (issue 45: ≤ 0.5 ms added);
#   - the runtime's frame at 3840 × 2160 and 1920 × 1080, FIS + depth, M = 16 (issue 45: ≤ 2 ms
#     at 4K);
#   - the glossy orders' frames (per point, per direction, per point visible) at 655 × 460 and
#     1280 × 720.
set -uo pipefail

KIT=.device-kit
# Vulkan's loader and what the runtime's headless device links, where the machine lacks them.
LOADER_PACKAGES="libvulkan1"

die() {
    echo "device-kit: $*" >&2
    exit 1
}

pack() {
    set -e
    cargo build --release --ignore-rust-version -p oslf
    cargo build --release --ignore-rust-version -p oslf-bevy --features viewer --example frame_cost
    local bench
    bench=$(cargo bench --ignore-rust-version -p oslf-runtime --bench frame --no-run 2>&1 |
        sed -n 's/.*Executable benches\/frame.rs (\(.*\))/\1/p' | tail -1)
    [ -n "$bench" ] && [ -x "$bench" ] || die "the frame bench's executable was not found"
    rm -rf "$KIT"
    mkdir -p "$KIT/bin" "$KIT/gl"
    for pair in "target/release/oslf:oslf" \
        "target/release/examples/frame_cost:frame_cost" \
        "$bench:frame-bench"; do
        strip -o "$KIT/bin/${pair#*:}" "${pair%%:*}"
        # gzip, not xz: a bare machine may lack xz.
        gzip -9 "$KIT/bin/${pair#*:}"
    done
    (cd "$KIT/gl" && apt-get download $LOADER_PACKAGES) ||
        echo "device-kit: the loader packages were not downloaded; the machine must have them" >&2
    git rev-parse HEAD >"$KIT/commit"
    du -sh "$KIT"
    echo "carry [\"$KIT\"] and run: bash scripts/device-kit.sh run"
}

# Seconds since the epoch, with fractions.
now() { date +%s.%N; }

# step NAME SECONDS COMMAND...: runs COMMAND under a timeout, its output in $OUT/NAME.log, and
# records its wall time in $OUT/NAME.wall; never stops the run.
step() {
    local name=$1 limit=$2
    shift 2
    echo "== $name: $*" | tee -a "$OUT/steps.log"
    local t0 rc
    t0=$(now)
    timeout "$limit" "$@" >"$OUT/$name.log" 2>&1
    rc=$?
    python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.2f}')" "$t0" "$(now)" >"$OUT/$name.wall"
    echo "   rc $rc, $(cat "$OUT/$name.wall") s" | tee -a "$OUT/steps.log"
    tail -3 "$OUT/$name.log" | sed 's/^/   | /' | tee -a "$OUT/steps.log"
    return 0
}

run() {
    local quick=false
    [ "${1:-}" = "--quick" ] && quick=true
    [ -d "$KIT/bin" ] || die "no $KIT/bin: run 'pack' here first and carry $KIT"
    OUT=${OUT:-$PWD/device-out}
    mkdir -p "$OUT"
    local work=/tmp/oslf-device-kit
    rm -rf "$work"
    mkdir -p "$work/bin" "$work/examples"
    for f in "$KIT"/bin/*.gz; do
        gzip -dc "$f" >"$work/bin/$(basename "$f" .gz)"
        chmod +x "$work/bin/$(basename "$f" .gz)"
    done
    # The loader, unless the machine has one; the NVIDIA driver's manifests where it keeps them.
    if ! ldconfig -p | grep -q libvulkan.so.1 && ls "$KIT"/gl/*.deb >/dev/null 2>&1; then
        for f in "$KIT"/gl/*.deb; do dpkg -x "$f" /; done
        ldconfig
    fi
    local icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    [ -f "$icd" ] && export VK_DRIVER_FILES=$icd
    # The examples with their stores beside them (the Bevy example reads examples/room.oslf).
    cp examples/*.toml examples/*.glb "$work/examples/"
    local oslf=$work/bin/oslf ex=$work/examples
    {
        echo "# device-kit run, $(date -u +%Y-%m-%dT%H:%MZ), commit $(cat "$KIT/commit" 2>/dev/null)"
        echo
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
        nproc
    } >"$OUT/machine.txt"

    # --quick (here, on a CPU adapter): the thesis preset's first cubes on the GPU path, the
    # other stores baked whole on the CPU, small frames, no other presets.
    local partial=() device=gpu bench_store=gazebo-cube64 size_bevy=(1920 1080 240)
    local sizes_frame=(3840x2160 1920x1080) rounds=9
    if $quick; then
        partial=(--max-cubes 12)
        device=cpu
        bench_store=gazebo-quick
        size_bevy=(320 180 12)
        sizes_frame=(320x180)
        rounds=1
    fi
    # bake NAME SCENE [PRESET [DEVICE [ARGS...]]]: a bake with its JSON report.
    bake() {
        local name=$1 scene=$2 preset=${3:-} on=${4:-$device}
        shift $(($# < 4 ? $# : 4))
        local args=("$ex/$scene.toml" -o "$work/$name.oslf" --device "$on" --preview none -q
            --report-json "$OUT/bake-$name.json" "$@")
        [ -n "$preset" ] && args+=(--preset "$preset")
        step "bake-$name" 300 "$oslf" bake "${args[@]}"
    }
    # The targets first: the gazebo's thesis preset, the room's default (auto: the GPU and its
    # [presets.gpu] where there is one), whose store the Bevy example then draws.
    bake gazebo-thesis gazebo thesis gpu "${partial[@]}"
    step bake-room-default 300 "$oslf" bake "$ex/room.toml" -o "$ex/room.oslf" --preview none -q \
        --report-json "$OUT/bake-room-default.json"
    mkdir -p "$OUT/bevy" "$OUT/bevy-ssao"
    (cd "$OUT/bevy" && OSLF_ASSETS=$ex step bevy-1080p 300 "$work/bin/frame_cost" "${size_bevy[@]}")
    (cd "$OUT/bevy-ssao" && OSLF_ASSETS=$ex step bevy-1080p-ssao 300 "$work/bin/frame_cost" --ssao "${size_bevy[@]}")
    if $quick; then
        bake gazebo-quick gazebo
    else
        bake gazebo-cube64 gazebo cube64
    fi
    for size in "${sizes_frame[@]}"; do
        OSLF_STORE=$work/$bench_store.oslf OSLF_BENCH_SIZE=$size OSLF_BENCH_ROUNDS=$rounds \
            OSLF_BENCH_FILTER="glossy ratio" OSLF_BENCH_CSV=$OUT/frame-$size.csv \
            step "frame-$size" 300 "$work/bin/frame-bench"
    done
    # The glossy orders' frames (per point, per direction, per point visible, per point
    # searched) at the bench's own sizes: what the costlier orders cost on this device.
    OSLF_STORE=$work/$bench_store.oslf OSLF_BENCH_FILTER="glossy M=16, per" \
        OSLF_BENCH_CSV=$OUT/frame-orders.csv step frame-orders 300 "$work/bin/frame-bench"
    if ! $quick; then
        # Every other example preset.
        bake gazebo-quick gazebo
        bake gazebo-gpu gazebo gpu
        bake gazebo-thesis-compact gazebo thesis-compact
        bake room-gpu room gpu
        bake room-gpu-dense room gpu-dense
        bake room-thesis room thesis
        bake orb-default orb
        bake orb-gpu orb gpu
        bake meshes-default meshes
        bake meshes-thesis meshes thesis
        bake can-default can
    fi
    summary >"$OUT/summary.md"
    cat "$OUT/summary.md"
}

# The summary of a run's output folder: bakes from their reports and wall times, the Bevy
# example's and the frame bench's own summaries.
summary() {
    echo "# device-kit figures"
    echo
    cat "$OUT/machine.txt"
    echo
    python3 - "$OUT" <<'PY'
import json, pathlib, sys
out = pathlib.Path(sys.argv[1])
print("| bake | capture device | cube maps | rays (closest + shadow) | Mrays/s | capture (s) | bake total (s) | wall (s) |")
print("| --- | --- | ---: | --- | ---: | ---: | ---: | ---: |")
for report in sorted(out.glob("bake-*.json")):
    name = report.stem[len("bake-"):]
    wall = (out / f"bake-{name}.wall").read_text().strip() if (out / f"bake-{name}.wall").exists() else "?"
    try:
        r = json.loads(report.read_text())
    except ValueError:
        print(f"| {name} | unreadable report | | | | | | {wall} |")
        continue
    num = lambda k, f: format(r[k], f) if isinstance(r.get(k), (int, float)) else "?"
    cubes = f"{r.get('cubes', '?')} of {r.get('cube_resolution', '?')}²"
    rays = f"{r.get('rays_closest', 0) / 1e6:.1f} M + {r.get('rays_shadow', 0) / 1e6:.1f} M"
    print(f"| {name} | {r.get('capture_device', '?')} | {cubes} | {rays} | {num('mrays_per_second', '.1f')} "
          f"| {num('capture_seconds', '.2f')} | {num('total_seconds', '.2f')} | {wall} |")
for name in sorted(p.stem for p in out.glob("bake-*.log")):
    if not (out / f"{name}.json").exists():
        print(f"| {name[len('bake-'):]} | failed: see {name}.log | | | | | | |")
PY
    for f in "$OUT"/bevy-*.log "$OUT"/frame-*.log; do
        [ -f "$f" ] || continue
        echo
        echo "## $(basename "$f" .log)"
        echo
        echo '```'
        grep -v -e XDG_RUNTIME_DIR -e $'\e\\[' "$f" | tail -24
        echo '```'
    done
}

case "${1:-}" in
pack) pack ;;
run)
    shift
    run "$@"
    ;;
summary)
    OUT=${2:-${OUT:-$PWD/device-out}}
    summary
    ;;
*) die "usage: device-kit.sh pack | run [--quick] | summary [DIR]" ;;
esac
