#!/usr/bin/env bash
# Wake-up latency of hapticd's servo loop against cyclictest (Debian rt-tests), on the same
# machine, back to back in the same run (docs/architecture.md §2.11). Both sleep to an
# absolute 1 ms deadline with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) in a SCHED_FIFO 80
# thread with mlockall and /dev/cpu_dma_latency = 0, unpinned, and measure wake - deadline:
#   cyclictest -m -p80 -i1000 -l N -q        (1 us histogram buckets)
#   hapticd --duration S --summary -         (the embedded default: sim device, demo wall,
#                                             real time; histogram buckets within 1.6 %)
# Needs root (SCHED_FIFO), cyclictest and jq.
#
# Usage: bench/wake_latency.sh [SECONDS] [HAPTICD]
#   SECONDS  length of each run (default 10: 10,000 wake-ups each)
#   HAPTICD  the daemon binary (default build/bench/bin/hapticd)
set -euo pipefail

seconds=${1:-10}
hapticd=${2:-build/bench/bin/hapticd}
loops=$((seconds * 1000))
hist_limit_us=10000 # cyclictest's histogram range; later wake-ups count as overflows

for tool in cyclictest jq "$hapticd"; do
    command -v "$tool" >/dev/null || {
        echo "wake_latency.sh: $tool not found" >&2
        exit 2
    }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "wake_latency.sh: $(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) cpus, kernel $(uname -r)," \
    "load $(cut -d' ' -f1-3 /proc/loadavg)"

echo "wake_latency.sh: cyclictest -m -p80 -i1000 -l $loops -q -h $hist_limit_us"
cyclictest -m -p80 -i1000 -l "$loops" -q -h "$hist_limit_us" --histfile="$work/hist" \
    >"$work/cyclictest.out"

echo "wake_latency.sh: $hapticd --duration $seconds --no-status --summary -"
"$hapticd" --duration "$seconds" --no-status --summary - >"$work/summary.json" \
    2>"$work/hapticd.log" || {
    echo "wake_latency.sh: hapticd failed:" >&2
    cat "$work/hapticd.log" >&2
    exit 1
}
sed 's/^/  /' "$work/hapticd.log"

# cyclictest: "bucket_us count" lines, then "# Histogram Overflows: N" and "# Max Latencies: M".
# Quantile q: the smallest bucket whose cumulative count reaches ceil(q * total), where the
# total includes the overflows (reported as "> limit").
read -r c_n c_p50 c_p99 c_p999 c_max < <(awk -v limit="$hist_limit_us" '
    /^[0-9]/ { count[$1 + 0] = $2 + 0; total += $2; next }
    /Histogram Overflows/ { overflows = $NF + 0 }
    /Max Latencies/ { max = $NF + 0 }
    function quantile(q,   need, sum, b) {
        need = int(q * n); if (need < q * n) need++
        for (b = 0; b < limit; b++) { sum += count[b]; if (sum >= need) return b }
        return ">" limit
    }
    END { n = total + overflows
          printf "%d %s %s %s %d\n", n, quantile(0.5), quantile(0.99), quantile(0.999), max }
' "$work/hist")

summary=$(cat "$work/summary.json")
h() { jq -r "$1" <<<"$summary"; }

printf '\n%-22s %14s %14s\n' "wake-up latency" "cyclictest" "hapticd"
printf '%-22s %14s %14s\n' "wake-ups" "$c_n" "$(h .ticks)"
printf '%-22s %14s %14.1f\n' "p50 (us)" "$c_p50" "$(h .wake_latency_us.p50)"
printf '%-22s %14s %14.1f\n' "p99 (us)" "$c_p99" "$(h .wake_latency_us.p99)"
printf '%-22s %14s %14.1f\n' "p99.9 (us)" "$c_p999" "$(h .wake_latency_us.p999)"
printf '%-22s %14s %14.1f\n' "max (us)" "$c_max" "$(h .wake_latency_us.max)"
printf '%-22s %14s %14s\n' "overruns (missed)" "-" "$(h .overruns) ($(h .missed_periods))"
echo
echo "hapticd real-time: $(h '.realtime | "SCHED_FIFO \(.sched_fifo) priority \(.priority), mlockall \(.memory_locked), cpu_dma_latency 0 \(.cpu_dma_latency_held), refused \(.refused)"')"
echo "hapticd exit: $(h .exit), faults $(jq -c .faults <<<"$summary")"
printf 'hapticd tick_compute_us: p50 %s, p99 %s, max %s\n' \
    "$(h .tick_compute_us.p50)" "$(h .tick_compute_us.p99)" "$(h .tick_compute_us.max)"
