#!/usr/bin/env bash
# Train on the GPU machine with the PyTorch trainer (trainer/arps_torch), fed by arps-train
# stream generators. The run lives outside the repository copy (RUN_ROOT), keeps training in the
# background (setsid) between calls, and every few minutes its newest checkpoint and log are
# copied to the output folder ($OUT), so a call cut off at its limit still returns the latest.
#
#   scripts/gpu-train.sh start NAME --minutes M [--from DIR] [--init "FLAGS"] [-- TRAINER FLAGS]
#       start a background session of M minutes for run NAME, then watch it (see watch).
#       --from DIR: resume from a carried run folder (checkpoint.safetensors or its .part-* pieces,
#       log.jsonl or log.jsonl.gz); --init "FLAGS": a new run (`arps-train init` flags);
#       --grow "FLAGS" with --from DIR: a wider copy of DIR's run (`arps-train grow` flags, e.g.
#       "--ffn-dim 512"), made on this machine, since its checkpoint is too large to carry.
#   scripts/gpu-train.sh watch NAME [SECONDS]   copy the newest state to $OUT every COLLECT_EVERY
#       seconds until the session ends or SECONDS (default 540) pass; the session goes on.
#   scripts/gpu-train.sh collect NAME           copy the newest state to $OUT once.
#   scripts/gpu-train.sh stop NAME              ask the session to stop (checkpoints, then ends).
#   scripts/gpu-train.sh join DIR RUN           here: rebuild RUN/ from a folder of collected files.
#
# Carried paths it reads (relative to the repository root; .gpu/ is git-ignored):
#   .gpu/arps-train          the x86-64 release binary (cargo build --release --features train)
#   .gpu/bank.arpsbank.gz    the packed shape bank (arps-train pack-bank)
# Environment: RUN_ROOT (default /tmp/arps-gpu), GENERATORS (default: cores - 2),
# COLLECT_EVERY (seconds, default 120), OUT (the output folder).
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$(pwd)
RUN_ROOT=${RUN_ROOT:-/tmp/arps-gpu}
BIN=${ARPS_TRAIN:-$REPO/.gpu/arps-train}
BANK=${ARPS_BANK:-$REPO/.gpu/bank.arpsbank.gz}
COLLECT_EVERY=${COLLECT_EVERY:-120}
GENERATORS=${GENERATORS:-$(( $(nproc) > 3 ? $(nproc) - 2 : 1 ))}
PART_SIZE=${PART_SIZE:-15M}

die() { echo "gpu-train: $*" >&2; exit 1; }

collect() {
    local run=$RUN_ROOT/$1 out=${OUT:?OUT is not set}
    [ -f "$run/checkpoint.safetensors" ] || { echo "gpu-train: no checkpoint yet in $run"; return 0; }
    local tmp=$out/.collect
    mkdir -p "$tmp"
    # a consistent snapshot: copy first (the trainer renames new checkpoints in atomically)
    cp "$run/checkpoint.safetensors" "$tmp/ckpt"
    cp "$run/checkpoint.json" "$tmp/checkpoint.json" 2>/dev/null || true
    [ -f "$run/best.safetensors" ] && cp "$run/best.safetensors" "$tmp/best.safetensors"
    gzip -c "$run/log.jsonl" > "$tmp/log.jsonl.gz"
    tail -n 40 "$run/train.out" > "$tmp/train-tail.txt" 2>/dev/null || true
    rm -f "$out"/checkpoint.safetensors.part-*
    split -b "$PART_SIZE" -d -a 1 "$tmp/ckpt" "$out/checkpoint.safetensors.part-"
    rm "$tmp/ckpt"
    mv "$tmp"/* "$out"/
    rmdir "$tmp"
    echo "gpu-train: collected step $(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['step'])" "$out/checkpoint.json" 2>/dev/null || echo '?') into $out"
}

running() { [ -f "$RUN_ROOT/$1/pid" ] && kill -0 "$(cat "$RUN_ROOT/$1/pid")" 2>/dev/null; }

watch() {
    local name=$1 limit=${2:-540} t0=$SECONDS
    while running "$name" && (( SECONDS - t0 + COLLECT_EVERY < limit )); do
        sleep "$COLLECT_EVERY"
        collect "$name"
    done
    running "$name" || echo "gpu-train: session ended"
    collect "$name"
}

# Rebuilds a run folder from pieces (checkpoint parts, gzipped log) in place.
assemble() {
    local dir=$1
    if ls "$dir"/checkpoint.safetensors.part-* >/dev/null 2>&1; then
        cat "$dir"/checkpoint.safetensors.part-* > "$dir/checkpoint.safetensors"
        rm "$dir"/checkpoint.safetensors.part-*
    fi
    if [ -f "$dir/log.jsonl.gz" ] && [ ! -f "$dir/log.jsonl" ]; then
        gunzip -c "$dir/log.jsonl.gz" > "$dir/log.jsonl" && rm "$dir/log.jsonl.gz"
    fi
}

cmd=${1:-}; shift || true
case "$cmd" in
start)
    name=${1:?run name}; shift
    minutes=""; from=""; init=""; grow=""
    while [ $# -gt 0 ]; do
        case "$1" in
        --minutes) minutes=$2; shift 2 ;;
        --from) from=$2; shift 2 ;;
        --init) init=$2; shift 2 ;;
        --grow) grow=$2; shift 2 ;;
        --) shift; break ;;
        *) die "unknown option $1" ;;
        esac
    done
    [ -n "$minutes" ] || die "--minutes is required"
    [ -z "$grow" ] || [ -n "$from" ] || die "--grow needs --from DIR"
    [ -x "$BIN" ] || die "$BIN is missing (carry .gpu/arps-train)"
    run=$RUN_ROOT/$name
    running "$name" && die "a session of $name is running"
    mkdir -p "$RUN_ROOT"
    if [ ! -f "$run/checkpoint.safetensors" ]; then
        if [ -n "$from" ] && [ -n "$grow" ]; then
            base=$RUN_ROOT/$name.base
            rm -rf "$base"; mkdir -p "$base"; cp -r "$from"/. "$base"/; assemble "$base"
            # shellcheck disable=SC2086
            "$BIN" grow --from "$base" --run "$run" $grow
        elif [ -n "$from" ]; then
            mkdir -p "$run"; cp -r "$from"/. "$run"/; assemble "$run"
        elif [ -n "$init" ]; then
            # shellcheck disable=SC2086
            "$BIN" init --run "$run" --bank "$BANK" $init
        else
            die "$run has no checkpoint: give --from DIR or --init FLAGS"
        fi
    fi
    bank_args=(); [ -f "$BANK" ] && bank_args=(--bank "$BANK")
    cd "$REPO/trainer"
    setsid nohup python3 -u -m arps_torch.train --run "$run" --arps-train "$BIN" --generators "$GENERATORS" \
        --minutes "$minutes" "${bank_args[@]}" "$@" > "$run/train.out" 2>&1 < /dev/null &
    echo $! > "$run/pid"
    cd "$REPO"
    echo "gpu-train: session of $name started (pid $(cat "$run/pid"), $GENERATORS generators, $minutes minutes)"
    if [ -n "${OUT:-}" ]; then watch "$name" "${WATCH_SECONDS:-540}"; fi
    ;;
watch) watch "${1:?run name}" "${2:-540}" ;;
collect) collect "${1:?run name}" ;;
stop) touch "$RUN_ROOT/${1:?run name}/STOP"; echo "gpu-train: asked $1 to stop" ;;
join)
    src=${1:?folder of collected files}; dst=${2:?run directory}
    mkdir -p "$dst"
    for f in "$src"/checkpoint.safetensors.part-* "$src"/checkpoint.json "$src"/best.safetensors "$src"/log.jsonl.gz; do
        [ -f "$f" ] && cp "$f" "$dst"/
    done
    rm -f "$dst/log.jsonl"
    assemble "$dst"
    echo "gpu-train: $dst rebuilt"
    ;;
*) sed -n '2,23p' "$0"; exit 2 ;;
esac
