#!/usr/bin/env bash
# Schema checks of deploy/, as CI runs them: the Dockerfile's COPY sources and Rust version,
# the Kubernetes manifests (kubernetes-validate --strict), the compose file (docker-compose
# config) and the systemd units (systemd-analyze verify). Builds nothing and starts nothing.
#
# Runs on a fresh Debian machine with only the Rust toolchain: as root it installs what it lacks
# (python3-venv, docker-compose) with apt-get and kubernetes-validate from PyPI into
# target/deploy-check/venv. A check that cannot run (no network, not root) prints
# `SKIPPED: <check> (<reason>)`; the exit status is non-zero only when a check ran and failed.
set -euo pipefail
cd "$(dirname "$0")/.."

# The oldest Kubernetes the manifests support (gRPC probes are GA in 1.27) and a recent one.
K8S_VERSIONS=${K8S_VERSIONS:-1.27.0 1.33.0}
KUBERNETES_VALIDATE=kubernetes-validate==1.37.0

work=target/deploy-check
mkdir -p "$work"
tmp=$(mktemp -d "$PWD/$work/tmp.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

passed=0 failed=0 skipped=0
pass() { echo "PASSED: $1"; passed=$((passed + 1)); }
fail() { echo "FAILED: $1"; failed=$((failed + 1)); }
skip() { echo "SKIPPED: $1 ($2)"; skipped=$((skipped + 1)); }
step() { printf '\n=== %s\n' "$1"; }

apt_updated=
# apt_install PACKAGE...: installs with apt-get when root; fails quietly otherwise.
apt_install() {
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null || return 1
    if [ -z "$apt_updated" ]; then
        apt-get update -qq >/dev/null 2>&1 || return 1
        apt_updated=1
    fi
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@" \
        >/dev/null 2>&1
}
why_no_apt() {
    if [ "$(id -u)" != 0 ]; then echo "not root"
    elif ! command -v apt-get >/dev/null; then echo "no apt-get"
    else echo "apt-get install $1 failed: no network?"
    fi
}

# --- Dockerfile ----------------------------------------------------------------------------
step "Dockerfile: COPY sources and Rust version"
dockerfile=deploy/Dockerfile
ignore=deploy/Dockerfile.dockerignore
ok=1
# The local sources of every COPY (not --from=stage copies nor here-documents): all words but the
# flags and the last, the destination.
sources=$(awk 'toupper($1) == "COPY" && !/--from=/ && !/<</ {
    n = 0
    for (i = 2; i <= NF; i++) if ($i !~ /^--/) w[++n] = $i
    for (i = 1; i < n; i++) print w[i]
}' "$dockerfile")
for src in $sources; do
    src=${src%/}
    if [ ! -e "$src" ]; then
        echo "  $dockerfile copies $src, which does not exist"
        ok=0
    fi
    # A literal pattern of the ignore file that covers the source would empty the COPY.
    while read -r pattern; do
        case $pattern in '' | '#'* | '!'* | *'*'* | *'?'* | *'['*) continue ;; esac
        pattern=${pattern%/}
        if [ "$src" = "$pattern" ] || [ "${src#"$pattern"/}" != "$src" ]; then
            echo "  $dockerfile copies $src, but $ignore excludes it ($pattern)"
            ok=0
        fi
    done <"$ignore"
done
# Cargo refuses a workspace with a member missing.
members=$(sed -n '/^members *=/,/]/p' Cargo.toml | grep -o '"[^"]*"' | tr -d '"')
for member in $members; do
    if ! grep -qx "$member" <<<"$sources"; then
        echo "  workspace member $member is not copied by $dockerfile"
        ok=0
    fi
done
# Files embedded at compile time by the members' sources must be copied too.
while IFS=: read -r file rel; do
    embedded=$(realpath -m --relative-to=. "$(dirname "$file")/$rel")
    covered=0
    for src in $sources; do
        src=${src%/}
        if [ "$embedded" = "$src" ] || [ "${embedded#"$src"/}" != "$embedded" ]; then covered=1; fi
    done
    if [ "$covered" = 0 ]; then
        echo "  $file embeds $embedded, which $dockerfile does not copy"
        ok=0
    fi
done < <(for member in $members; do
    [ -d "$member/src" ] \
        && grep -roE 'include_(str|bytes)!\("[^"]+"\)' --include='*.rs' "$member/src"
done | sed -E 's/:include_(str|bytes)!\("([^"]+)"\)$/:\2/')
if [ "$ok" = 1 ]; then pass "Dockerfile sources"; else fail "Dockerfile sources"; fi

# The builder's Rust must be at least every locked crate's rust-version (cargo refuses older
# ones, and --locked forbids picking other versions). Read from the crates cargo has downloaded.
rust=$(sed -n 's/^ARG RUST_VERSION=\([0-9.]*\).*/\1/p' "$dockerfile" | cut -d. -f1,2)
registry=${CARGO_HOME:-$HOME/.cargo}/registry/src
found=0
need="0.0 nothing"
# newer A B: true when version B is above version A.
newer() { [ "$(printf '%s\n' "$1" "$2" | sort -V | tail -1)" != "$1" ]; }
while read -r pkg; do
    for toml in "$registry"/*/"$pkg"/Cargo.toml; do
        [ -f "$toml" ] || continue
        found=$((found + 1))
        version=$(sed -n 's/^rust-version *= *"\([0-9.]*\)".*/\1/p' "$toml" | cut -d. -f1,2)
        if [ -n "$version" ] && newer "${need% *}" "$version"; then need="$version $pkg"; fi
    done
done < <(awk '/^name = / { n = $3 } /^version = / { v = $3 } /^source = "registry/ {
    gsub(/"/, "", n); gsub(/"/, "", v); print n "-" v }' Cargo.lock)
if [ -z "$rust" ]; then
    fail "Dockerfile Rust version (no ARG RUST_VERSION=X.Y)"
elif [ "$found" = 0 ]; then
    skip "Dockerfile Rust version" "no locked crate downloaded in $registry: run cargo fetch"
elif newer "$rust" "${need% *}"; then
    echo "  ${need#* } needs Rust ${need% *}; $dockerfile builds with $rust"
    fail "Dockerfile Rust version"
else
    pass "Dockerfile Rust $rust >= the rust-version of $found locked crates (${need#* }: ${need% *})"
fi

# --- Kubernetes ----------------------------------------------------------------------------
step "Kubernetes manifests"
k8s=deploy/k8s
# kustomization.yaml is no Kubernetes object: check that what it lists exists, and that every
# manifest is listed but secret.yaml (a template, kept out on purpose).
ok=1
listed=$(awk '/^resources:/ { on = 1; next } /^[^ #-]/ { on = 0 } on && $1 == "-" { print $2 }' \
    "$k8s/kustomization.yaml")
for resource in $listed; do
    if [ ! -e "$k8s/$resource" ]; then
        echo "  kustomization.yaml lists $resource, which does not exist"
        ok=0
    fi
done
for manifest in "$k8s"/*.yaml; do
    name=$(basename "$manifest")
    case $name in kustomization.yaml | secret.yaml) continue ;; esac
    if ! grep -qx "$name" <<<"$listed"; then
        echo "  $name is not listed in kustomization.yaml"
        ok=0
    fi
done
if [ "$ok" = 1 ]; then pass "kustomization.yaml"; else fail "kustomization.yaml"; fi

venv=$work/venv
validator=$venv/bin/kubernetes-validate
setup_validator() {
    [ -e "$venv/.installed-$KUBERNETES_VALIDATE" ] && return 0
    if ! command -v python3 >/dev/null || ! python3 -c 'import ensurepip, venv' 2>/dev/null; then
        apt_install python3 python3-venv || {
            why="python3 with venv missing: $(why_no_apt python3-venv)"
            return 1
        }
    fi
    rm -rf "$venv"
    python3 -m venv "$venv" >/dev/null || { why="python3 -m venv failed"; return 1; }
    "$venv/bin/pip" install -q --disable-pip-version-check "$KUBERNETES_VALIDATE" >/dev/null 2>&1 \
        || { why="pip install $KUBERNETES_VALIDATE failed: no network?"; rm -rf "$venv"; return 1; }
    touch "$venv/.installed-$KUBERNETES_VALIDATE"
}
# validate_manifests WHAT FILE...: every file, strictly, against each Kubernetes version.
validate_manifests() {
    local what=$1 version
    shift
    for version in $K8S_VERSIONS; do
        if "$validator" --strict --quiet -k "$version" "$@"; then
            pass "kubernetes-validate --strict -k $version ($# $what)"
        else
            fail "kubernetes-validate --strict -k $version ($what)"
        fi
    done
}
# validate_rendered DIR [KINDS]: what `kubectl apply -k DIR` would send (the kustomization's
# namespace and image applied), validated against the newest version; with KINDS, the sorted
# kinds it holds (each followed by a space) must be those.
validate_rendered() {
    local dir=$1 kinds=${2:-} rendered version=${K8S_VERSIONS##* }
    rendered="$tmp/$(basename "$dir").yaml"
    if ! command -v kubectl >/dev/null; then
        skip "kubectl kustomize $dir" "no kubectl"
    elif ! kubectl kustomize "$dir" >"$rendered" 2>"$tmp/err"; then
        cat "$tmp/err"
        fail "kubectl kustomize $dir"
    elif [ -n "$kinds" ] && [ "$(awk '/^kind:/ { print $2 }' "$rendered" | sort | tr '\n' ' ')" != "$kinds" ]; then
        fail "kubectl kustomize $dir renders $(awk '/^kind:/ { print $2 }' "$rendered" | sort | tr '\n' ' ')"
    elif "$validator" --strict --quiet -k "$version" "$rendered"; then
        pass "kubectl kustomize $dir, validated against $version"
    else
        fail "kubectl kustomize $dir, validated against $version"
    fi
}
why=
if setup_validator; then
    manifests=$(find "$k8s" -maxdepth 1 -name '*.yaml' ! -name kustomization.yaml | sort)
    # shellcheck disable=SC2086 # the names hold no spaces
    validate_manifests files $manifests
    validate_rendered "$k8s"
else
    skip "kubernetes-validate" "$why"
fi

# --- Kubernetes, the fleet overlay ---------------------------------------------------------
step "Kubernetes fleet overlay (deploy/k8s-fleet)"
fleet=deploy/k8s-fleet
# Its own manifests, strictly; the CloudNativePG example is a custom resource with no schema
# here: it must parse and be the operator's Cluster.
fleet_manifests=$(find "$fleet" -maxdepth 1 -name '*.yaml' ! -name kustomization.yaml \
    ! -name cloudnativepg.yaml | sort)
if [ -x "$validator" ]; then
    # shellcheck disable=SC2086 # the names hold no spaces
    validate_manifests "fleet files" $fleet_manifests
    if "$venv/bin/python" - "$fleet/cloudnativepg.yaml" <<'PY'
import sys, yaml
doc = yaml.safe_load(open(sys.argv[1]))
assert doc["apiVersion"] == "postgresql.cnpg.io/v1" and doc["kind"] == "Cluster", doc
spec = doc["spec"]
assert spec["instances"] >= 2 and spec["postgresql"]["synchronous"]["number"] >= 1, spec
PY
    then
        pass "cloudnativepg.yaml: a CloudNativePG Cluster with a synchronous standby"
    else
        fail "cloudnativepg.yaml"
    fi
    # The overlay as `kubectl apply -k` sends it: the base's single coordinator replaced by two.
    validate_rendered "$fleet" \
        "Deployment Deployment HorizontalPodAutoscaler Namespace PodDisruptionBudget Service "
else
    skip "kubernetes-validate (fleet)" "$why"
fi

# --- compose -------------------------------------------------------------------------------
step "compose file"
composers=()
command -v docker-compose >/dev/null && composers+=("docker-compose")
if command -v docker >/dev/null && docker compose version >/dev/null 2>&1; then
    composers+=("docker compose")
fi
if [ ${#composers[@]} = 0 ]; then
    # Debian bookworm's docker-compose 1.29.2: `config` needs no Docker daemon.
    if apt_install docker-compose; then
        composers+=("docker-compose")
    else
        skip "docker-compose config" \
            "no docker-compose nor docker compose; $(why_no_apt docker-compose)"
    fi
fi
if [ ${#composers[@]} -gt 0 ]; then
    # Throwaway tokens, so that no check depends on (or leaves) files in deploy/secrets.
    printf 'check-client-token\n' >"$tmp/client.token"
    printf 'check-worker-token\n' >"$tmp/worker.token"
    for composer in "${composers[@]}"; do
        # shellcheck disable=SC2086 # "docker compose" is two words
        if env -u COMPOSE_FILE -u COMPOSE_PROJECT_NAME RESTAURO_SECRETS_DIR="$tmp" \
            $composer -f deploy/compose.yaml config -q; then
            pass "$composer config ($($composer version --short 2>/dev/null || echo '?'))"
        else
            fail "$composer -f deploy/compose.yaml config"
        fi
    done
fi

# --- systemd -------------------------------------------------------------------------------
step "systemd units"
units=(deploy/systemd/*.service)
if ! command -v systemd-analyze >/dev/null; then
    skip "systemd-analyze verify" "no systemd-analyze"
else
    # In a root of its own: the units' ExecStart binaries need not be installed on this machine.
    root=$tmp/systemd-root
    mkdir -p "$root/etc/systemd/system" "$root/usr/local/bin" "$root/usr/lib/systemd"
    cp -a /usr/lib/systemd/system "$root/usr/lib/systemd/" 2>/dev/null || true
    cp "${units[@]}" "$root/etc/systemd/system/"
    sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "${units[@]}" | while read -r binary; do
        printf '#!/bin/sh\n' >"$root$binary" && chmod +x "$root$binary"
    done
    names=("${units[@]##*/}")
    # verify exits 0 on unknown keys and the like, so any complaint about our units fails too.
    if systemd-analyze verify --root="$root" "${names[@]}" >"$tmp/verify" 2>&1 \
        && ! grep -qF "$(printf '%s\n' "${names[@]}")" "$tmp/verify"; then
        pass "systemd-analyze verify (${names[*]})"
    else
        cat "$tmp/verify"
        fail "systemd-analyze verify"
    fi
fi

echo
echo "deploy-check: $passed passed, $failed failed, $skipped skipped"
[ "$failed" = 0 ]
