#!/bin/sh
# Runs the benchmarks of bench/README.md's table one after the other, as the docs quote them, each writing its
# own results file. Before each one it waits until the machine is quiet -- the CPU at least 95 % idle over one
# second, checked for up to 2 minutes -- so that the tail of one run (a Dask cluster shutting down, page cache
# writes) does not weigh on the next.
#
#   sh bench/run_all.sh                      # all of them, about 12 minutes on the project's 2-core machine
#   sh bench/run_all.sh solvers povray       # some: solvers gen render startup blas view animation povray gallery
set -e
cd "$(dirname "$0")/.."
BIN=.venv/bin

idle_percent() { # CPU idle over one second, from /proc/stat
    set -- $(head -1 /proc/stat)
    t1=$(($2 + $3 + $4 + $5 + $6 + $7 + $8)) i1=$5
    sleep 1
    set -- $(head -1 /proc/stat)
    t2=$(($2 + $3 + $4 + $5 + $6 + $7 + $8)) i2=$5
    echo $((100 * (i2 - i1) / (t2 - t1 + 1)))
}

settle() {
    n=0
    while [ "$(idle_percent)" -lt 95 ] && [ $n -lt 120 ]; do n=$((n + 1)); done
    echo "== $1 ($(date -u '+%H:%M:%S') UTC, waited $n s for a quiet machine)"
}

run() {
    case $1 in
    solvers) $BIN/implgen bench solvers ;;
    gen) $BIN/implgen bench gen ;;
    render) $BIN/implgen bench render --fold-compare ;;
    startup) $BIN/python bench/startup.py ;;
    blas) $BIN/python bench/blas_threads.py ;;
    view) $BIN/python bench/view_latency.py ;;
    animation) $BIN/python bench/animation.py ;;
    povray) $BIN/python bench/povray_compare.py --runs 5 ;;
    gallery) $BIN/python bench/gallery.py ;;
    esac
}

ALL="solvers gen render startup blas view animation povray gallery"
[ $# -gt 0 ] || set -- $ALL
for b in "$@"; do # every name checked before the first long run
    case " $ALL " in
    *" $b "*) ;;
    *) echo "bench/run_all.sh: unknown benchmark '$b'" >&2 && exit 2 ;;
    esac
done
for b in "$@"; do
    settle "$b"
    run "$b"
done
