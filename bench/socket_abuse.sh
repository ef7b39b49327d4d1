#!/usr/bin/env bash
# The servo loop while clients hammer the control socket (docs/benchmarks.md, "The servo
# under socket abuse"): wake-up latency and tick compute, side by side in the same run, for
#   quiet   hapticd --socket with no client
#   cpu     the same with one core kept busy (stress-ng --cpu 1): what CPU load alone does
#   cpu2    both cores kept busy (stress-ng --cpu 2), as the hammer's threads keep them
#   hammer  the same with socket_hammer: floods, garbage, oversized lines, connect churn,
#           half-closes, idle clients, a polite client polling status as fast as it can,
#           sixteen busy clients that hold every place, subscribers that never read, slow
#           readers, and a disarm every 50 ms whose latency socket_hammer prints (so this
#           arm's servo is mostly disarmed)
#   flood, garbage, connect, busy, streams, slow
#           one of socket_hammer's storms alone (its file comment), with the disarm probe:
#           the disarm's latency under each storm (issue 28); not in the default ARMS
#   other   socket_hammer on a second hapticd's socket, not this one's: the same load on the
#           machine, none of it on this process (what is the machine's, what is hapticd's);
#           with SERVO_CPU, that hapticd runs unpinned on the clients' CPUs
#   stream  the heaviest use that is meant: 15 `hapticctl stream --rate 100` subscribers and
#           a `hapticctl record` of every tick, for SECONDS
# each SECONDS long, real time, the embedded default (sim device, demo wall), as root
# (SCHED_FIFO 80, mlockall); ROUNDS rounds of the arms, interleaved, so that the machine's
# drift falls on all of them alike. Prints each run, then the medians over the rounds, then
# for the arms with the disarm probe its latency: p50 and p99 as medians over the rounds,
# the max and the disarms that failed over all of them.
#
# Usage: [ARMS="quiet hammer ..."] [SERVO_CPU=N] bench/socket_abuse.sh [SECONDS] [ROUNDS] [BIN]
#   SECONDS    how long the clients of each run go on (default 10); the servo runs 1 s longer
#   ROUNDS     rounds of the arms (default 3)
#   BIN        the directory of hapticd, hapticctl and socket_hammer (default build/bench/bin)
#   ARMS       which arms, in this order (default all six; quiet must be one of them)
#   SERVO_CPU  pin the servo thread to this CPU ([servo] cpu = N, which keeps hapticd's other
#              threads off it) and run the clients and stress-ng on the other CPUs, as a lab
#              PC with an isolated servo core would (default: unpinned)
set -euo pipefail

seconds=${1:-10}
rounds=${2:-3}
bin=${3:-build/bench/bin}
arms=${ARMS:-quiet cpu cpu2 hammer other stream}
servo_cpu=${SERVO_CPU:-}
python=/usr/bin/python3
for tool in "$bin/hapticd" "$bin/hapticctl" "$bin/socket_hammer" stress-ng "$python"; do
    command -v "$tool" >/dev/null || {
        echo "socket_abuse.sh: $tool not found" >&2
        exit 2
    }
done

case " $arms " in *" quiet "*) ;; *) echo "socket_abuse.sh: ARMS must hold quiet" >&2; exit 2 ;; esac

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
config=()
clients=()
if [ -n "$servo_cpu" ]; then
    # The embedded default with the servo pinned; its scene path made absolute.
    "$python" - "$PWD/config/hapticd.toml" "$servo_cpu" >"$work/pinned.toml" <<'PY'
import pathlib, re, sys
path, cpu = pathlib.Path(sys.argv[1]), sys.argv[2]
text = path.read_text().replace('file = "scenes/', f'file = "{path.parent}/scenes/')
print(re.sub(r"^\[servo\]\n", f"[servo]\ncpu = {cpu}\n", text, count=1, flags=re.M), end="")
PY
    config=(--config "$work/pinned.toml")
    others=$("$python" -c "import os; print(','.join(str(c) for c in sorted(os.sched_getaffinity(0)) if c != $servo_cpu))")
    clients=(taskset -c "$others")
fi
placement="servo unpinned"
[ -n "$servo_cpu" ] && placement="servo on cpu $servo_cpu, clients on cpus $others"
echo "socket_abuse.sh: $(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) cpus, kernel $(uname -r)," \
    "load $(cut -d' ' -f1-3 /proc/loadavg); $rounds rounds of $seconds s; $placement"

for round in $(seq "$rounds"); do
    for arm in $arms; do
        socket="$work/$arm-$round.sock"
        summary="$work/$arm-$round.json"
        # One second longer than the clients run, so that the disarm probe never meets a
        # daemon that has ended (a disarm without a reply is a failure).
        "$bin/hapticd" "${config[@]}" --duration "$((seconds + 1))" --no-status --socket "$socket" \
            --summary "$summary" 2>"$work/$arm-$round.log" &
        daemon=$!
        for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.05; done
        case $arm in
            cpu) "${clients[@]}" stress-ng --cpu 1 --timeout "${seconds}s" --quiet ;;
            cpu2) "${clients[@]}" stress-ng --cpu 2 --timeout "${seconds}s" --quiet ;;
            hammer) "${clients[@]}" "$bin/socket_hammer" "$socket" "$seconds" all \
                | tee "$work/$arm-$round.hammer" ;;
            flood | garbage | connect | busy | streams | slow)
                "${clients[@]}" "$bin/socket_hammer" "$socket" "$seconds" "$arm" \
                    | tee "$work/$arm-$round.hammer" ;;
            other)
                "${clients[@]}" "$bin/hapticd" --duration "$((seconds + 3))" --no-status \
                    --socket "$work/other.sock" 2>/dev/null &
                other=$!
                for _ in $(seq 100); do [ -S "$work/other.sock" ] && break; sleep 0.05; done
                "${clients[@]}" "$bin/socket_hammer" "$work/other.sock" "$seconds"
                kill "$other" 2>/dev/null || true
                wait "$other" 2>/dev/null || true
                ;;
            stream)
                streams=()
                for _ in $(seq 15); do
                    "${clients[@]}" timeout -s INT "$seconds" "$bin/hapticctl" --socket "$socket" \
                        stream --rate 100 >/dev/null &
                    streams+=($!)
                done
                # A run the overrun budget ended early (a host stall) has no socket left to
                # stop the recording on: its summary says so, and the table shows the fault.
                "$bin/hapticctl" --socket "$socket" record start "$work/take-$round.csv" \
                    >/dev/null || echo "round $round: record start failed" >>"$work/records.txt"
                sleep "$seconds"
                "$bin/hapticctl" --socket "$socket" record stop >>"$work/records.txt" 2>&1 ||
                    echo "round $round: record stop failed" >>"$work/records.txt"
                wait "${streams[@]}" || true
                ;;
        esac
        # A host stall may exhaust the overrun budget (exit 1, the fault in the summary, which
        # the table shows); no summary at all is a failure.
        wait "$daemon" || [ -s "$summary" ] || {
            echo "socket_abuse.sh: hapticd ($arm, round $round) failed:" >&2
            cat "$work/$arm-$round.log" >&2
            exit 1
        }
    done
done

"$python" - "$work" "$rounds" "$arms" <<'PY'
import json, os, re, statistics, sys
work, rounds, arms = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
fields = [("wake p50", "wake_latency_us", "p50"), ("wake p99", "wake_latency_us", "p99"),
          ("compute p50", "tick_compute_us", "p50"), ("compute p99", "tick_compute_us", "p99")]
runs = {arm: [json.load(open(f"{work}/{arm}-{r}.json")) for r in range(1, rounds + 1)]
        for arm in arms}
print("run                 " + "".join(f"{name:>13}" for name, _, _ in fields)
      + "     ticks  overruns  faults")
for r in range(rounds):
    for arm in arms:
        s = runs[arm][r]
        print(f"{arm + ' ' + str(r + 1):<20}"
              + "".join(f"{s[k][q]:>10.2f} us" for _, k, q in fields)
              + f"{s['ticks']:>10}{s['overruns']:>10}  {','.join(s['faults']) or 'none'}")
print("median over rounds")
for arm in arms:
    print(f"{arm:<20}" + "".join(
        f"{statistics.median(s[k][q] for s in runs[arm]):>10.2f} us" for _, k, q in fields))
quiet = {f: statistics.median(s[k][q] for s in runs["quiet"]) for f, k, q in fields}
for arm in (a for a in arms if a != "quiet"):
    print(f"{arm + ' / quiet':<20}" + "".join(
        f"{statistics.median(s[k][q] for s in runs[arm]) / quiet[f]:>13.2f}"
        for f, k, q in fields))
probes = {arm: [open(f"{work}/{arm}-{r}.hammer").read() for r in range(1, rounds + 1)]
          for arm in arms if os.path.exists(f"{work}/{arm}-1.hammer")}
if probes:
    print("disarm under each storm   carried out   failed      p50      p99      max")
    probe = re.compile(r"disarm: (\d+) carried out, (\d+) failed; latency p50 (\S+) ms, "
                       r"p99 (\S+) ms, max (\S+) ms")
for arm, texts in probes.items():
    runs = [[float(v) for v in probe.search(t).groups()] for t in texts]
    print(f"{arm:<25}{sum(r[0] for r in runs):>12.0f}{sum(r[1] for r in runs):>9.0f}"
          f"{statistics.median(r[2] for r in runs):>6.2f} ms"
          f"{statistics.median(r[3] for r in runs):>6.2f} ms{max(r[4] for r in runs):>6.2f} ms")
PY
if [ -s "$work/records.txt" ]; then
    echo "recordings of the stream arm (hapticctl record stop):"
    cat "$work/records.txt"
fi
