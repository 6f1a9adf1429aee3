#!/usr/bin/env bash
# A PostgreSQL server for the fleet tests (issue 40): Debian's package, a cluster of its own in a
# temporary folder on 127.0.0.1:54329, stopped by its pid.
#   .ci/postgres.sh start DIR   installs PostgreSQL if missing, starts it, prints the test URL
#   .ci/postgres.sh restart DIR restarts it (fast: sessions cut, as a database failover does)
#   .ci/postgres.sh stop DIR    stops the server started in DIR
set -euo pipefail
cmd=$1 dir=$2
port=${RESTAURO_PG_PORT:-54329}
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
case $cmd in
start)
    if [ -z "$bin" ]; then
        $sudo apt-get update -qq
        $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq postgresql >/dev/null
        bin=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -1)
    fi
    mkdir -p "$dir"
    # PostgreSQL does not run as root: as root, the cluster belongs to the package's user.
    as=()
    if [ "$(id -u)" -eq 0 ]; then
        chown postgres "$dir"
        as=(runuser -u postgres --)
    fi
    "${as[@]}" "$bin/initdb" -D "$dir/data" -U postgres --auth=trust -E UTF8 >"$dir/initdb.log"
    "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w \
        -o "-p $port -k $dir -c listen_addresses=127.0.0.1 -c fsync=on" start >/dev/null
    "${as[@]}" "$bin/psql" -h 127.0.0.1 -p "$port" -U postgres -qc \
        "CREATE ROLE restauro LOGIN CREATEDB PASSWORD 'restauro'" >/dev/null
    echo "postgres://restauro:restauro@127.0.0.1:$port/postgres"
    ;;
restart)
    as=()
    [ "$(id -u)" -eq 0 ] && as=(runuser -u postgres --)
    "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -m fast -w restart >/dev/null
    ;;
stop)
    pid=$(head -1 "$dir/data/postmaster.pid" 2>/dev/null || true)
    if [ -n "$pid" ]; then
        kill -INT "$pid" 2>/dev/null || true
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    fi
    ;;
esac
