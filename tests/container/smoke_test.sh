#!/usr/bin/env bash
# Container smoke test (issue: web page and container demo): builds docker/Dockerfile with podman
# (no Docker engine on our machines; see ../shared/CONTAINERS.md), starts it, uploads a map, runs a
# short mission through the published port, checks the health check, stops it.
#   tests/container/smoke_test.sh [PORT]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
port=${1:-18480}
image=roverplan:smoke
name=roverplan-smoke-$$
state=${ROVERPLAN_CONTAINER_STATE:-/var/tmp/roverplan-container}
passed=0
fail() { echo "FAIL: $*" >&2; podman --runtime runc logs "$name" 2>/dev/null | tail -20 >&2 || true; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }

missing=()
for p in podman runc debootstrap; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
mkdir -p "$state"
# What this sandbox forbids: raising RLIMIT_NOFILE and systemd cgroups (CONTAINERS.md).
cat > "$state/containers.conf" <<'CONF'
[containers]
default_ulimits = []
[engine]
cgroup_manager = "cgroupfs"
CONF
export CONTAINERS_CONF="$state/containers.conf"
pm() { podman --runtime runc "$@"; }

# No registry is reachable here: the base image is made from Debian's own packages, from the same
# mirror the host's apt uses.
if ! pm image exists docker.io/library/debian:bookworm-slim; then
  mirror=$(sed -n 's/^URIs: *\([^ ]*\).*/\1/p' /etc/apt/sources.list.d/*.sources 2>/dev/null | head -1)
  [ -n "$mirror" ] || mirror=$(awk '$1 == "deb" {print $2; exit}' /etc/apt/sources.list 2>/dev/null)
  [ -n "$mirror" ] || fail "no Debian mirror found in the host's apt sources"
  rm -rf "$state/rootfs"
  debootstrap --variant=minbase bookworm "$state/rootfs" "$mirror" >/dev/null
  tar -C "$state/rootfs" -c . | pm import - docker.io/library/debian:bookworm-slim >/dev/null
  rm -rf "$state/rootfs"
fi
pass "base image debian:bookworm-slim"

# npm inside the build must trust the same CAs as this host (the sandbox inspects HTTPS).
ca_args=()
if [ -f /etc/ssl/certs/ca-certificates.crt ]; then
  ca_args=(-v /etc/ssl/certs/ca-certificates.crt:/tmp/host-ca.crt:ro --build-arg NODE_EXTRA_CA_CERTS=/tmp/host-ca.crt)
fi
pm build --format docker --network host --pull=never "${ca_args[@]}" -t "$image" -f "$root/docker/Dockerfile" "$root" > "$state/build.log" 2>&1 \
  || { tail -30 "$state/build.log" >&2; fail "podman build"; }
pass "image builds from docker/Dockerfile"

[ "$(pm image inspect "$image" --format '{{.Config.User}}')" = roverplan ] || fail "the image does not run as the roverplan user"
pm image inspect "$image" --format '{{json .Config.Healthcheck}}' > "$state/healthcheck.json"
grep -q api/health "$state/healthcheck.json" || fail "no HEALTHCHECK on /api/health"
pass "non-root user and a HEALTHCHECK"

pm run -d --rm --network host --name "$name" "$image" \
  roverplan serve --host 127.0.0.1 --port "$port" --data /var/lib/roverplan/data >/dev/null
trap 'podman --runtime runc stop -t 2 "$name" >/dev/null 2>&1 || true' EXIT
url="http://127.0.0.1:$port"
for _ in $(seq 1 150); do curl -fs "$url/api/health" >/dev/null 2>&1 && break; sleep 0.2; done
# (Bodies go to files first: with pipefail, `curl | grep -q` fails when grep stops reading early.)
curl -fs "$url/api/health" > "$state/health.json" && grep -q '"status":"ok"' "$state/health.json" || fail "health"
curl -fs "$url/" > "$state/index.html" && grep -qi "<html" "$state/index.html" || fail "the web page is not served"
pass "container serves the API and the web page (found without --web)"

pm exec "$name" roverplan terrain --preset moon --size 64 --cell 1 --seed 2 --out /tmp/moon.tif >/dev/null
pm cp "$name:/tmp/moon.tif" "$state/moon.tif"
map=$(curl -fs "$url/api/maps?name=moon&filename=moon.tif" -H 'Content-Type: image/tiff' --data-binary @"$state/moon.tif" \
  | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])') || fail "upload"
mission=$(curl -fs "$url/api/missions" -H 'Content-Type: application/json' \
  -d "{\"map\":\"$map\",\"planner\":\"coverage\",\"rovers\":[{\"x\":10,\"y\":10,\"heading\":0}],\"params\":{\"coverage\":0.8}}" \
  | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])') || fail "mission"
for _ in $(seq 1 100); do
  status=$(curl -fs "$url/api/missions/$mission" | python3 -c 'import json,sys; print(json.load(sys.stdin)["status"])')
  [ "$status" = succeeded ] && break
  sleep 0.2
done
[ "$status" = succeeded ] || fail "mission status $status"
curl -fs "$url/api/missions/$mission/result.geojson" > "$state/result.geojson" && grep -q FeatureCollection "$state/result.geojson" || fail "result"
pass "upload a map and run a mission through the published port"

pm stop -t 5 "$name" >/dev/null
trap - EXIT
pass "container stops"
echo "$passed passed, 0 failed"
