#!/usr/bin/env bash
# Multi-host test of a restauro cluster on one machine: a coordinator and two workers, each in
# its own network namespace ("host"), joined by a Linux bridge. Mid-job, worker w1's link is
# cut; w2 must finish the job, and the assembled image must be bit-identical to an in-process
# render of the same scene. Needs root and network namespaces; elsewhere it prints SKIPPED and
# exits 0.
#
#   deploy/netns-test.sh
#   BIN_DIR=path/to/bin SPP=64 KEEP_WORK=1 deploy/netns-test.sh
#
# BIN_DIR holds restauro, restauro-coordinator and restauro-worker (default: target/release of
# this repository). KEEP_WORK=1 keeps the scratch folder (logs, results) after a passing run;
# after a failing one it is always kept.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN_DIR=${BIN_DIR:-$ROOT/target/release}
# Tuned so the job takes 10-20 s on 2 cores with two 1-thread workers, one of them cut early.
SPP=${SPP:-64}
WIDTH=480 HEIGHT=270 TILE=32
CUT_AFTER=20 # tiles w1 starts before its link is cut: past the cheap sky rows at the top, early
            # enough that most of the job is left for w2
# The PID keeps namespace names unique between parallel runs. Interface names need no suffix:
# every veth is created inside this run's own switch namespace, and names are per namespace.
ID=$$
NS_SW=rst-sw-$ID NS_C=rst-coord-$ID NS_W1=rst-w1-$ID NS_W2=rst-w2-$ID
COORD_IP=10.77.0.1
URL=http://$COORD_IP:7878
R=restauro # replaced by the absolute path once BIN_DIR is checked
export NO_COLOR=1 # plain logs, readable when their tails are printed

START=$SECONDS
WORK=""
PIDS=()       # every process this script started, stopped by id in cleanup
NAMESPACES=() # every namespace this script created

step() { printf '[%3ds] %s\n' $((SECONDS - START)) "$*"; }
skip() { echo "SKIPPED: multi-host test ($1)"; exit 0; }
fail() { echo "FAIL: $*"; exit 1; }

any_alive() { local p; for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && return 0; done; return 1; }
cleanup() {
    local rc=$? pid ns f n
    set +e
    trap '' INT TERM # a second Ctrl-C must not cut the cleanup short
    # Processes go first: a namespace with a process in it outlives `ip netns del`, and so
    # would its veth end and the bridge. SIGTERM lets them shut down, but a worker finishing a
    # tile for a coordinator that is gone (or behind a cut link) keeps trying to hand it in,
    # so whatever is left after 3 s gets SIGKILL.
    for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for ((n = 0; n < 30; n++)); do any_alive || break; sleep 0.1; done
    for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; done
    for ns in "${NAMESPACES[@]}"; do
        # Anything still inside our own namespaces (say, a stray child) is ours too.
        for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null; done
        ip netns del "$ns" 2>/dev/null || echo "warning: could not delete namespace $ns"
    done
    if [[ -n $WORK && -d $WORK ]]; then
        if ((rc == 130 || rc == 143)); then
            echo "interrupted; kept $WORK"
        elif ((rc != 0)); then
            for f in "$WORK"/*.log; do
                [[ -s $f ]] && printf -- '--- last lines of %s\n%s\n' "$f" "$(tail -n 15 "$f")"
            done
            echo "kept $WORK for inspection"
        elif [[ ${KEEP_WORK:-} == 1 ]]; then
            echo "kept $WORK"
        else
            rm -rf "$WORK"
        fi
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# wait_for SECONDS WHAT COMMAND...: poll COMMAND every 0.1 s; fail if it takes longer or if
# one of our processes has died meanwhile (a crash would otherwise look like a slow cluster).
wait_for() {
    local limit=$1 what=$2 pid
    shift 2
    local end=$((SECONDS + limit))
    until "$@"; do
        ((SECONDS < end)) || fail "timed out after ${limit}s waiting for $what"
        for pid in "${PIDS[@]}"; do
            kill -0 "$pid" 2>/dev/null || fail "process $pid exited while waiting for $what"
        done
        sleep 0.1
    done
}
# The client runs on the coordinator's host and talks to it over the bridge address.
client() { ip netns exec "$NS_C" "$R" "$@" --coordinator "$URL" --token-file "$WORK/client.token"; }
lines() { if [[ -f $1 ]]; then wc -l <"$1"; else echo 0; fi; }
pings() { ip netns exec "$1" ping -q -c1 -W1 "$COORD_IP" >/dev/null 2>&1; }
tcp_open() { ip netns exec "$1" timeout 1 bash -c "exec 3<>/dev/tcp/$COORD_IP/7878" 2>/dev/null; }
token() { head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n'; }
# 1. Preconditions.
[[ $(id -u) == 0 ]] || skip "not root"
command -v ip >/dev/null || skip "no ip command"
for b in restauro restauro-coordinator restauro-worker; do
    [[ -x $BIN_DIR/$b ]] || fail "no $BIN_DIR/$b; build with cargo build --release"
done
BIN_DIR=$(cd "$BIN_DIR" && pwd) # absolute: commands run inside namespaces and folders
R=$BIN_DIR/restauro
WORK=$(mktemp -d "${TMPDIR:-/tmp}/restauro-netns.XXXXXX")
if ! ip netns add "$NS_SW" 2>"$WORK/netns.err"; then
    # A name left by a run killed with SIGKILL is our problem, not the environment's.
    ! grep -q 'exists' "$WORK/netns.err" || fail "namespace $NS_SW exists already"
    skip "ip netns add failed: $(head -n 1 "$WORK/netns.err")"
fi
NAMESPACES+=("$NS_SW")
step "binaries from $BIN_DIR, scratch folder $WORK"

# 2. The network: one bridge in the switch namespace, a veth from it to each host.
step "network: bridge br0 in $NS_SW; $NS_C 10.77.0.1, $NS_W1 .2, $NS_W2 .3"
ip -n "$NS_SW" link set lo up
ip -n "$NS_SW" link add name br0 type bridge
ip -n "$NS_SW" link set br0 up
i=1
for host in coord w1 w2; do
    ns=rst-$host-$ID
    ip netns add "$ns"
    NAMESPACES+=("$ns")
    ip -n "$NS_SW" link add name "p-$host" type veth peer name eth0 netns "$ns"
    ip -n "$NS_SW" link set "p-$host" master br0 up
    ip -n "$ns" link set lo up
    ip -n "$ns" addr add "10.77.0.$i/24" dev eth0
    ip -n "$ns" link set eth0 up
    i=$((i + 1))
done
if command -v ping >/dev/null; then
    for ns in "$NS_W1" "$NS_W2"; do
        wait_for 5 "ping from $ns to $COORD_IP" pings "$ns"
    done
    step "ping from both worker hosts to the coordinator host: ok"
else
    step "no ping here: connectivity is checked by TCP once the coordinator listens"
fi

# 3. The scene and the two tokens (distinct: the coordinator refuses equal ones).
step "scene: restauro scene aosta ${WIDTH}x${HEIGHT}"
"$R" scene aosta --out "$WORK/scene" --width "$WIDTH" --height "$HEIGHT" >"$WORK/scene.log" 2>&1
SCENE=$WORK/scene/aosta.toml
(umask 077 && token >"$WORK/client.token" && token >"$WORK/worker.token")
! cmp -s "$WORK/client.token" "$WORK/worker.token" || fail "the two tokens are equal"

# 4. The cluster. Short timeouts so the lost worker is noticed within seconds.
step "coordinator in $NS_C on $COORD_IP:7878 (heartbeat timeout 2 s, lease timeout 20 s)"
ip netns exec "$NS_C" "$BIN_DIR/restauro-coordinator" --listen "$COORD_IP:7878" \
    --data "$WORK/data" --client-token-file "$WORK/client.token" \
    --worker-token-file "$WORK/worker.token" --heartbeat-timeout-s 2 --lease-timeout-s 20 \
    >"$WORK/coordinator.log" 2>&1 &
PIDS+=($!)
for ns in "$NS_W1" "$NS_W2"; do
    wait_for 10 "a TCP connection from $ns to $COORD_IP:7878" tcp_open "$ns"
done
step "TCP from both worker hosts to the coordinator: ok"
for w in w1 w2; do
    ip netns exec "rst-$w-$ID" "$BIN_DIR/restauro-worker" --coordinator "$URL" \
        --token-file "$WORK/worker.token" --name "$w" --threads 1 --cache "$WORK/$w-cache" \
        --tile-log "$WORK/$w.tiles" >"$WORK/$w.log" 2>&1 &
    PIDS+=($!)
done
both_registered() { [[ $(client workers 2>/dev/null | grep -cE ' w[12] ') == 2 ]]; }
wait_for 15 "both workers to register" both_registered
step "workers w1 in $NS_W1 and w2 in $NS_W2 registered (1 render thread each)"

# 5. Submit, then cut w1 off mid-job.
OPTS=(--variant as-found --spp "$SPP" --width "$WIDTH" --height "$HEIGHT" --tile "$TILE")
JOB=$(client submit "$SCENE" "${OPTS[@]}" 2>"$WORK/submit.log")
SUBMITTED=$SECONDS
step "submitted job $JOB (${OPTS[*]})"
w1_started() { (($(lines "$WORK/w1.tiles") >= CUT_AFTER)); }
wait_for 60 "w1 to start $CUT_AFTER tiles" w1_started
ip -n "$NS_SW" link set p-w1 down
CUT_EPOCH=$(date +%s.%N)
W1_CUT=$(lines "$WORK/w1.tiles") W2_CUT=$(lines "$WORK/w2.tiles")
CUT_S=$((SECONDS - SUBMITTED))
step "CUT w1's link at $(date +%T.%3N), ${CUT_S} s into the job;" \
    "tiles so far: w1 $W1_CUT, w2 $W2_CUT"

# 6. The job must finish on w2 alone. (--foreground: timeout would otherwise move `watch` out
# of our process group, and Ctrl-C would wait for the job instead of stopping it.)
timeout --foreground 90 ip netns exec "$NS_C" "$R" watch "$JOB" --coordinator "$URL" \
    --token-file "$WORK/client.token" >"$WORK/watch.log" 2>&1 || true
JOB_S=$((SECONDS - SUBMITTED))
grep -q "job $JOB done" "$WORK/watch.log" ||
    fail "(a) job $JOB did not complete: $(tail -n 1 "$WORK/watch.log")"
W1_END=$(lines "$WORK/w1.tiles") W2_END=$(lines "$WORK/w2.tiles")
# Attempts count from 1: a second attempt is a tile whose lease w1 held when it was lost.
RETRIED=$(awk '$3 > 1' "$WORK/w2.tiles" | wc -l)
step "(a) job done in ${JOB_S} s: $(client jobs | grep "^$JOB" | tr -s ' ' | cut -d' ' -f2-4)"
((W2_END > W2_CUT)) || fail "(b) w2 rendered no tile after the cut"
step "(b) after the cut w2 rendered $((W2_END - W2_CUT)) tiles ($RETRIED re-leased from w1)," \
    "w1 $((W1_END - W1_CUT))"
# The coordinator logs each lease it takes back from a silent worker; only w1 went silent.
NOTICED=$(grep -m1 'lease expired' "$WORK/coordinator.log" | cut -d' ' -f1 || true)
if [[ -n $NOTICED ]]; then
    step "(b) the coordinator took w1's lease back $(awk -v a="$(date -d "$NOTICED" +%s.%N)" \
        -v b="$CUT_EPOCH" 'BEGIN { printf "%.1f", a - b }') s after the cut"
fi
client fetch "$JOB" --out "$WORK/cluster" >"$WORK/fetch.log" 2>&1
step "fetched the results into $WORK/cluster"

step "reference: the same render in-process"
"$R" render "$SCENE" --in-process "${OPTS[@]}" --out "$WORK/local" >"$WORK/local.log" 2>&1
# Both paths write the same attributes (variant, integrator, spp, depth, seed; no times or
# hosts), in name order: the files must be equal byte for byte, the absolute XYZ and the Retinex.
for EXR in aosta-as-found.exr aosta-as-found-retinex.exr; do
    for d in cluster local; do [[ -s $WORK/$d/$EXR ]] || fail "no $d/$EXR"; done
    cmp "$WORK/cluster/$EXR" "$WORK/local/$EXR" ||
        fail "(c) the cluster's $EXR differs from the in-process one"
    step "(c) $EXR from the cluster and in-process: byte-identical"
done

# 7. Summary.
echo "PASS: multi-host test in $((SECONDS - START)) s: job $JOB done in $JOB_S s; w1 cut after" \
    "$W1_CUT tiles at ${CUT_S} s, w2 rendered $W2_CUT before and $((W2_END - W2_CUT)) after;" \
    "XYZ and Retinex EXRs byte-identical to the in-process render"
