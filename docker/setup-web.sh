#!/usr/bin/env bash
# Installs the browser libraries of the web page (and of the browser tests, and the OpenAPI linters
# of tests/contract) from npm, as pinned by their package-lock.json files; does nothing when they
# are already installed. Node.js and npm come from Debian when the machine has none.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if ! command -v npm >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
for dir in "$@"; do
  [ -f "$root/$dir/package.json" ] || continue
  stamp="$root/$dir/node_modules/.package-lock.json"
  if [ ! -f "$stamp" ] || [ "$root/$dir/package-lock.json" -nt "$stamp" ]; then
    (cd "$root/$dir" && npm ci --no-audit --no-fund --loglevel=error)
  fi
done
