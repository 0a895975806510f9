#!/bin/bash
# Packs and loads several of seed 001's sandstones at the seed's size side by side on a machine
# lent for a few minutes (16 cores, no Open MPI or Breccia installed), and leaves what a table
# needs in OUT. Run by hand, not by CI:
#
#   bench/carry-openmpi build/breccia      # here: a portable build and its libraries in .mpi/
#   # there, carrying .mpi:
#   validation/tumlin-full-size/lent-machine.sh OUT STOP_S brenna:8 radkow:8
#
# Each ROCK:THREADS runs `run.sh pack 1` and `run.sh run 1 fast` with that many threads; every run
# still going after STOP_S seconds is sent SIGTERM, so it stops with its interim analysis (the
# checkpoint it also writes stays behind). OUT receives each run folder's small files
# (ROCK.tgz), its crack catalogue (ROCK-cracks.csv.gz), table.py's tables (tables.md) and the
# logs, `/usr/bin/time -v` reports and the machine's description (logs.tgz).
set -uo pipefail
cd "$(dirname "$0")/../.."
out=$1 stop_s=$2 scale=${SCALE:-1}  # SCALE < 1 tries the script on a smaller cylinder
shift 2
. .mpi/env.sh
export BRECCIA=$PWD/.mpi/bin/breccia
logs=$(mktemp -d)
{ nproc; grep -m1 "model name" /proc/cpuinfo; free -g | head -2; } > "$logs/machine.txt"
pids=()
for job in "$@"; do
  rock=${job%:*} threads=${job#*:}
  (
    export ROCK=$rock THREADS=$threads
    validation/tumlin-full-size/run.sh pack "$scale" && exec validation/tumlin-full-size/run.sh run "$scale" fast
  ) > "$logs/$rock.log" 2>&1 &
  pids+=($!)
done
# SIGTERM to the processes of this script's binary (not the wrappers, whose /usr/bin/time must
# report, nor any other breccia on the machine).
(sleep "$stop_s" && pkill -TERM -f "^$BRECCIA ") &
watchdog=$!
wait "${pids[@]}"
kill "$watchdog" 2> /dev/null
args=()
for job in "$@"; do
  rock=${job%:*}
  folder=$(ls -d runs/"$rock"/"$scale"-fast/*/ 2> /dev/null | tail -1)
  [ -n "$folder" ] || continue
  for f in runs/"$rock"/pack-"$scale".time runs/"$rock"/run-"$scale"-fast.time; do
    [ -f "$f" ] && cp "$f" "$logs/$rock-$(basename "$f")"
  done
  tar czf "$out/$rock.tgz" -C "$folder" --exclude='checkpoint*' --exclude=cracks.csv \
    --exclude=report.html --exclude=snapshots --exclude=report .
  gzip -c "$folder/cracks.csv" > "$out/$rock-cracks.csv.gz"
  args+=("$rock=$folder,runs/$rock/run-$scale-fast.time")
done
python3 validation/tumlin-full-size/table.py "${args[@]}" > "$out/tables.md" 2>&1
tar czf "$out/logs.tgz" -C "$logs" .
ls -la "$out"
