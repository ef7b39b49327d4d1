"""The firmware in the loop: the reference firmware's binary on an emulated ATmega328P in an
emulated Hapkit paddle (hapticd-avr-sim --clock lockstep, docs/firmware.md), driven over its
serial link by the unchanged daemon.

  delay   the paced loop's delay as `haptic-tune diag --lockstep` measures it on the board
  wall    the stiffest coupling k_c the board holds stably against a stiff wall, hands-off,
          bisected: kicked in contact (0.5 N for 10 ms), the handle's oscillation judged by
          `haptic-tune plot-run` (it decays: stable; it grows: unstable); beside it the
          passive model's k_c without the delay (2b/T, what a design that ignores the link
          would use) and with the measured delay (what autotune sizes)
"""

import os
import signal
import subprocess
import time

import designs as design_models
import hil
from context import EvidenceError
from hil import number

PADDLE = hil.Device(mass_kg=0.05, damping_n_s_per_m=0.5, rate_hz=1000.0)  # the harness's
COUNTS_PER_METER = 81572.06200906535  # the firmware's (docs/firmware.md)
FLOOR_M = 3.0 / COUNTS_PER_METER
WALL_SCENE = ('[scene]\nname = "fil-wall"\naxes = 1\n[[wall]]\nnormal = [-1.0]\noffset = 0.0\n'
              'stiffness = 1e5\ndamping = 0.0\n[[spring]]\nanchor = [0.01]\nstiffness = 200.0\n')
KICK = ["--push", "0.5", "--push-start", "1.0", "--push-duration", "0.01"]
JUDGE_FROM_S = 1.05
RUN_S = 5.0


class Board:
    """hapticd-avr-sim running the firmware, its serial port at `link`; stopped on exit."""

    def __init__(self, ctx, work, options):
        self.link = work / "hapkit"
        elf = ctx.bin_dir.parent / "firmware" / "hapkit.elf"
        if not elf.is_file():
            raise EvidenceError(f"{elf} is missing: the firmware is built with the project "
                                "(gcc-avr, HAPTICD_FIRMWARE)")
        self.process = subprocess.Popen(
            [ctx.program("hapticd-avr-sim"), "--firmware", str(elf), "--link", str(self.link),
             "--clock", "lockstep", *options],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            start_new_session=True)
        until = time.monotonic() + 20.0
        while not os.path.exists(self.link):
            if self.process.poll() is not None or time.monotonic() > until:
                self.__exit__(None, None, None)
                raise EvidenceError(f"hapticd-avr-sim did not start: {self.process.stderr.read()}")
            time.sleep(0.002)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.process.stderr.close()


def board_config(port, coupling_stiffness_n_per_m, scene_path):
    return ('[servo]\nrate_hz = 1000.0\nrealtime = "off"\n'
            '[device]\nplugin = "serial"\naxes = 1\n'
            f'[device.serial]\nport = "{port}"\n'
            '[safety]\nmax_force = 4.0\nmax_speed = 1.0\n'
            f"[device.model]\nmass = {number(PADDLE.mass_kg)}\n"
            f"damping = {number(PADDLE.damping_n_s_per_m)}\ndelay = 0.0005\n"
            f"[coupling]\nstiffness = {number(coupling_stiffness_n_per_m)}\ndamping = 0.0\n"
            'check = "off"\n'
            f'[scene]\nfile = "{scene_path}"\n')


def measured_delay(ctx):
    work = ctx.scratch("fil-diag")
    with Board(ctx, work, []) as board:
        config = work / "cfg.toml"
        config.write_text(board_config(board.link, 100.0, work / "scene.toml"))
        (work / "scene.toml").write_text(WALL_SCENE)
        report = ctx.run_json([ctx.program("haptic-tune"), "diag", "--lockstep", "--duration",
                               "0.5" if ctx.quick else "2", "--json", "--config", str(config)],
                              "haptic-tune diag on the emulated board")
    delay = report["loop_delay"]
    if not delay.get("measured"):
        raise EvidenceError("haptic-tune diag measured no loop delay on the emulated board")
    return {"p50_periods": delay["periods"]["p50"], "p99_periods": delay["periods"]["p99"],
            "protocol_version": delay["protocol_version"]}


def kicked(ctx, stiffness_n_per_m, tag):
    """One kicked contact on a fresh board; its judgement."""
    work = ctx.scratch(tag)
    (work / "scene.toml").write_text(WALL_SCENE)
    log = work / "run.csv"
    with Board(ctx, work, KICK) as board:
        (work / "cfg.toml").write_text(board_config(board.link, stiffness_n_per_m,
                                                    work / "scene.toml"))
        ctx.run([ctx.program("hapticd"), "--lockstep", "--no-status", "--duration",
                 number(RUN_S), "--config", str(work / "cfg.toml"), "--log", str(log),
                 "--summary", str(work / "summary.json")], f"hapticd on the board ({tag})")
    judged = ctx.run_json([ctx.program("haptic-tune"), "plot-run", str(log), "--json",
                           "--from", number(JUDGE_FROM_S), "--window", "0.05",
                           "--floor", number(FLOOR_M)], f"plot-run ({tag})")
    log.unlink()
    return {"stiffness_n_per_m": stiffness_n_per_m, "growth_per_s": judged["growth_per_s"],
            "peak_amplitude_m": judged["peak_amplitude_m"],
            "faults": [f["fault"] for f in judged["faults"]],
            # Kicked, the oscillation either decays from the kick or grows from it.
            "stable": judged["growth_per_s"] < 0.0}


def run(ctx):
    delay = measured_delay(ctx)
    delay_s = round(delay["p99_periods"] / 0.05 + 0.4999) * 0.05 / PADDLE.rate_hz  # as autotune
    passive = design_models.Design("passive", "", "", ())
    without_delay = design_models.sized_stiffness(ctx, PADDLE, passive, 0.0)
    delayed_paddle = hil.Device(PADDLE.mass_kg, PADDLE.damping_n_s_per_m, PADDLE.rate_hz, delay_s)
    with_delay = design_models.sized_stiffness(ctx, delayed_paddle, passive, 0.0)
    low, high = 0.5 * with_delay, 1.5 * without_delay
    runs = ctx.parallel(lambda k: kicked(ctx, k, f"fil-end-{k:g}"), [low, high])
    if runs[0]["stable"] and not runs[1]["stable"]:
        for step in range(3 if ctx.quick else 7):
            middle = (low * high) ** 0.5
            verdict = kicked(ctx, middle, f"fil-{step}")
            runs.append(verdict)
            low, high = (middle, high) if verdict["stable"] else (low, middle)
        bracket = {"stiffest_stable_n_per_m": low, "first_unstable_n_per_m": high}
    else:
        bracket = {"stiffest_stable_n_per_m": None, "first_unstable_n_per_m": None}
    return {"device": (f"the emulated Hapkit paddle m = {PADDLE.mass_kg:g} kg, "
                       f"b = {PADDLE.damping_n_s_per_m:g} N s/m, 1000 Hz, the reference "
                       "firmware's binary on an emulated ATmega328P over its serial link"),
            "delay": delay, "sized_delay_s": delay_s,
            "passive_without_delay_n_per_m": without_delay,
            "passive_with_delay_n_per_m": with_delay, "wall_n_per_m": 1e5,
            "measured": bracket, "runs": sorted(runs, key=lambda r: r["stiffness_n_per_m"])}


def draw(data, out_dir, caption):
    import chart_style
    written = []
    what = ("The reference firmware in the loop: the kicked contact's growth against k_c on "
            "the emulated board, and the passive model's k_c without and with the measured "
            "delay")
    for extension in ("png", "pdf"):
        plt, _ = chart_style.pyplot()
        figure = chart_style.new_figure(plt, (7.0, 4.2))
        ax = figure.subplots()
        runs = data["runs"]
        ks = [r["stiffness_n_per_m"] for r in runs]
        growth = [r["growth_per_s"] for r in runs]
        ax.plot(ks, growth, color="0.3", linewidth=1.0, zorder=1)
        for r in runs:
            ax.plot([r["stiffness_n_per_m"]], [r["growth_per_s"]],
                    marker="o" if r["stable"] else "X", markersize=8, linestyle="none",
                    color="tab:blue" if r["stable"] else "tab:red", zorder=2)
        ax.plot([], [], "o", color="tab:blue", label="measured: decays (stable)")
        ax.plot([], [], "X", color="tab:red", label="measured: grows (unstable)")
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.axvline(data["passive_without_delay_n_per_m"], color="tab:green", linestyle=":",
                   linewidth=1.6, label="passive model without the delay: k_c = "
                   f"{data['passive_without_delay_n_per_m']:,.0f} N/m")
        ax.axvline(data["passive_with_delay_n_per_m"], color="tab:green", linestyle="--",
                   linewidth=1.6, label=f"passive model with the measured delay "
                   f"({1e3 * data['sized_delay_s']:.2f} ms): k_c = "
                   f"{data['passive_with_delay_n_per_m']:,.0f} N/m")
        ax.set_xscale("log")
        ax.set_xlabel("coupling stiffness k_c (N/m)")
        ax.set_ylabel("growth of the kicked contact (1/s)")
        chart_style.grid(ax)
        chart_style.save(figure, str(out_dir / f"firmware-in-the-loop.{extension}"),
                         f"{what}. {caption}", legend_from=[ax])
        plt.close(figure)
        written.append(f"firmware-in-the-loop.{extension}")
    return written


