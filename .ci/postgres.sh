#!/usr/bin/env bash
# A PostgreSQL server for the fleet tests (issue 40): Debian's package, a cluster of its own in a
# temporary folder on 127.0.0.1:54329, stopped by its pid. It speaks TLS (and plain TCP) with a
# certificate for 127.0.0.1 and localhost signed by a certificate authority of its own,
# DIR/tls/ca.crt, which the TLS tests trust; the role restauro_cert logs in (to its database
# restauro_cert) over TLS with the client certificate DIR/tls/client.{crt,key} only.
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
    # The authority and the server's certificate (openssl comes with Debian's PostgreSQL).
    tls=$dir/tls
    mkdir -p "$tls"
    openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes -days 2 \
        -subj "/CN=restauro test authority" -keyout "$tls/ca.key" -out "$tls/ca.crt" 2>/dev/null
    openssl req -new -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes \
        -subj "/CN=localhost" -keyout "$tls/server.key" -out "$tls/server.csr" 2>/dev/null
    printf 'subjectAltName=DNS:localhost,IP:127.0.0.1\n' >"$tls/server.ext"
    openssl x509 -req -in "$tls/server.csr" -CA "$tls/ca.crt" -CAkey "$tls/ca.key" \
        -CAcreateserial -days 2 -extfile "$tls/server.ext" -out "$tls/server.crt" 2>/dev/null
    openssl req -new -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes \
        -subj "/CN=restauro_cert" -keyout "$tls/client.key" -out "$tls/client.csr" 2>/dev/null
    printf 'extendedKeyUsage=clientAuth\n' >"$tls/client.ext"
    openssl x509 -req -in "$tls/client.csr" -CA "$tls/ca.crt" -CAkey "$tls/ca.key" \
        -CAcreateserial -days 2 -extfile "$tls/client.ext" -out "$tls/client.crt" 2>/dev/null
    chmod 600 "$tls/server.key" "$tls/client.key"
    [ "$(id -u)" -eq 0 ] && chown -R postgres "$tls"
    # Client certificates, first match: restauro_cert by its certificate alone.
    "${as[@]}" sed -i "1i hostssl all restauro_cert 127.0.0.1/32 cert" "$dir/data/pg_hba.conf"
    "${as[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w \
        -o "-p $port -k $dir -c listen_addresses=127.0.0.1 -c fsync=on -c ssl=on \
            -c ssl_cert_file=$tls/server.crt -c ssl_key_file=$tls/server.key \
            -c ssl_ca_file=$tls/ca.crt" start >/dev/null
    "${as[@]}" "$bin/psql" -h 127.0.0.1 -p "$port" -U postgres -q \
        -c "CREATE ROLE restauro LOGIN CREATEDB PASSWORD 'restauro'" \
        -c "CREATE ROLE restauro_cert LOGIN" \
        -c "CREATE DATABASE restauro_cert OWNER restauro_cert" >/dev/null
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
