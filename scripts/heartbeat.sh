#!/bin/sh
# Run a command, printing "rvsm setup: still LABEL (N s)" every 8 s while it runs, so no
# step of `make setup` waits more than 10 s without a line (pip's downloads and wheel
# builds, apt, yowasp's first compile). Exits with the command's status; an interrupt
# ends the command too.  Usage: scripts/heartbeat.sh LABEL COMMAND [ARG ...]
label=$1
shift
"$@" &
pid=$!
trap 'kill "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; exit 130' INT TERM
ticks=0
while kill -0 "$pid" 2>/dev/null; do
  sleep 1
  ticks=$((ticks + 1))
  if [ $((ticks % 8)) -eq 0 ] && kill -0 "$pid" 2>/dev/null; then
    echo "rvsm setup: still $label ($ticks s)" >&2
  fi
done
wait "$pid"
