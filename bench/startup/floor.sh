#!/bin/sh
# The floor of bench/startup: starts N copies of PROG as a binary tree (process i needs
# process (i-1)/2 ready) with nothing but this shell, each one as soon as its parent printed
# "ready".  Every process writes its line into one FIFO, which the shell reads in the order
# the lines come.  Prints "all N ready"; then, on a line on stdin, stops them all (SIGTERM,
# wait) and prints "stopped".
# usage: floor.sh PROG TOKEN DIR N   (DIR: an empty scratch directory for the FIFO)
set -u
prog=$1 token=$2 dir=$3 n=$4
mkfifo "$dir/ready"
exec 3<>"$dir/ready"  # read-write: opening does not block and the FIFO never sees EOF
pids=""
start() {
    "$prog" "$token" "p$1" >&3 &
    pids="$pids $!"
}
start 0
count=0
while [ "$count" -lt "$n" ] && read -r word name <&3; do
    if [ "$word" != ready ]; then
        echo "floor.sh: unexpected line: $word $name" >&2
        kill -TERM $pids
        exit 1
    fi
    count=$((count + 1))
    i=${name#p}
    for child in $((2 * i + 1)) $((2 * i + 2)); do
        if [ "$child" -lt "$n" ]; then
            start "$child"
        fi
    done
done
echo "all $count ready"
read -r _ || true
kill -TERM $pids
wait
echo stopped
