#!/usr/bin/python3
"""Hostile, independent check of `haptic-tune ... --model exact --operator-class FILE`.

An independent numpy model of the sampled-data haptic loop (written from the model's
description, not from src/tune/), a search of a declared operator class x environments for
a closed-loop spectral radius > 1 + 1e-8, and a comparison with the tool's limits.

The model. Device m dv/dt + b v = F_h - F, sampled every T. The continuous state is the
handle (x, v) and, for a two-mass grasp, the hand (x_h, v_h):
    handle --(k_s, b_s)-- hand mass m_h --(k_a, b_a)-- ground        (hands-off: no hand)
sampled exactly (zero-order hold, scipy.linalg.expm of the augmented matrix). Tick n:
x_d[n] = x(nT), v_d[n] = (x_d[n] - x_d[n-1])/T,
F[n] = k_c (x_d[n] - x_e[n]) + b_c (v_d[n] - v_e[n]), v_e the backward difference of x_e,
F[n] held over [nT + dT, (n+1)T + dT) (d whole periods of delay: a delay line of forces).
Environments are written as F[n] = H(z) x_e[n] (H = N(z^-1)/D(z^-1)) and the algebraic loop
with the coupling is solved for x_e[n] every tick:
    wall           x_e = 0
    implicit       H = m_e s_b^2 + b_e s_b + k_e,        s_b = (1 - z^-1)/T   (implicit Euler)
    lossless       H = (m_e s + k_e/s) s_b,              s = (2/T)(1 - z^-1)/(1 + z^-1)
    lossless2      two lossless mass-springs in parallel (an extra attack, beyond the brief)
Stability: the spectral radius of the closed-loop transition matrix <= 1 + 1e-8. When
nothing anchors the position (no wall, k_e = 0, and no hand with k_s > 0 and k_a > 0) the
loop has one free mode at z = 1; the search's objective drops the eigenvalue nearest 1 in
that case (and checks it is within 1e-8 of 1), so the landscape is not flat at 1.

Usage (from the repository's root, with Debian's /usr/bin/python3: numpy, scipy, mpmath):
    tools/scripts/class_adversary.py validate [--tool BIN]
        hands-off wall limits, and single-point classes compared with `haptic-tune check`
    tools/scripts/class_adversary.py limits [--tool BIN]
        the tool's class limits (size) for b_c in {0, 0.5, 1} x delay in {0, 1 ms},
        all passive environments and --scene god-object-sphere (rigid wall only)
    tools/scripts/class_adversary.py attack [--tool BIN] [--factors F,...] [--budget S]
        [--cases LIST] [--seed N] [--out results.json]
        search the class box x environments at each factor x each limit; every find
        > 1 + 1e-8 is written to a single-point class file (build/class-adversary/) and
        re-checked with `haptic-tune check --model exact --operator-class FILE`
    tools/scripts/class_adversary.py quick [--tool BIN] [--cls FILE] [--factor 0.999] [--budget S]
        CI's quick mode (three ctests, tests/tune/CMakeLists.txt): the tool's proven class
        limits for b_c 0.5 and no delay, b_c 1 and one period, and b_c 0.5 with the
        rigid-wall scene, each attacked at --factor x the limit for S CPU seconds; exit 1 if
        any find is confirmed in mpmath
    tools/scripts/class_adversary.py point --kc K --bc B [--delay-periods D] --op ... --env ...
        the spectral radius of one configuration (for checks by hand)
    tools/scripts/class_adversary.py own-limits [--budget S]
        the adversary's own class limit per case: bisection on the worst configuration
        found, a focused search just below it, repeated while that finds more, then a
        Nelder-Mead polish of that configuration at its critical k_c
    tools/scripts/class_adversary.py window [--tool BIN] [--own-limits FILE]
        where the tool's `check --operator-class` verdict flips, against own-limits' limits
        (bisection between the adversary's limit and the tool's rejected stiffness)

Defaults: --tool build/release/bin/haptic-tune (the build tree's, from `cmake --preset
release`), the class config/operators/pen-grip.toml, m = 0.1 kg, b = 2 N s/m, 1 kHz. Scratch
files (class files, the limit cache) go to build/class-adversary/. Every find is re-checked
in mpmath before it counts: a near-defective pair at z = 1 (a free 1e5 kg virtual mass) or an
extreme two-mode lossless environment puts double-precision radii up to ~3e-4 off.

What the attacks found, and what each fix changed, is in docs/stability-models.md ("Attacked
by an independent implementation", "In CI, against the proof"): the full attack
(`attack --factors 0.995,1.01 --budget 15`) takes about 11 minutes of CPU.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import scipy.linalg
import scipy.optimize

# The independent model, from this script's own folder.
from class_adversary_model import (
    B_DEV,
    M_DEV,
    OP_KEYS,
    T,
    TOL,
    parse_class,
    closed_loop_mp,
    simulate_lossless,
    spectral,
    objective_radius,
    u_to_val,
    val_to_u,
    op_from_u,
    env_from_y,
    ENV_BOX,
)

# The build tree's haptic-tune, from the repository's root.
TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "build", "release",
                    "bin", "haptic-tune")
CLASS_FILE = "config/operators/pen-grip.toml"
WALL_SCENE = "config/scenes/god-object-sphere.toml"

# The declared class (pen-grip.toml), parsed below; these are the fallback values.
CLASS = {
    "hand_mass": (0.1, 2.0),
    "grip_stiffness": (0.0, 3000.0),
    "grip_damping": (2.0, 30.0),
    "arm_stiffness": (0.0, 1000.0),
    "arm_damping": (0.0, 20.0),
}


# ---------------------------------------------------------------------------- the tool


def run_tool(tool, args):
    r = subprocess.run([tool] + args, capture_output=True, text=True)
    try:
        js = json.loads(r.stdout)
    except json.JSONDecodeError:
        js = None
    return r.returncode, js, r.stderr


def device_args(bc, delay_s):
    return ["--mass", str(M_DEV), "--damping", str(B_DEV), "--rate", str(1.0 / T),
            "--coupling-damping", repr(bc), "--delay", repr(delay_s), "--model", "exact"]


def tool_size(tool, bc, delay_s, cls_file, scene=None):
    args = ["size"] + device_args(bc, delay_s) + ["--operator-class", cls_file, "--json"]
    if scene:
        args += ["--scene", scene]
    rc, js, err = run_tool(tool, args)
    if js is None:
        raise SystemExit("size failed: %s" % err)
    return js


def tool_check(tool, kc, bc, delay_s, cls_file, scene=None):
    args = ["check"] + device_args(bc, delay_s) + ["--stiffness", repr(kc),
                                                   "--operator-class", cls_file, "--json"]
    if scene:
        args += ["--scene", scene]
    rc, js, err = run_tool(tool, args)
    return rc, js, err


def write_point_class(path, op):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("# a single-point operator class written by tools/scripts/class_adversary.py\n")
        f.write("[operator]\n")
        for k, v in zip(OP_KEYS, op):
            f.write("%s = %r\n" % (k, float(v)))
    return path


# ---------------------------------------------------------------------------- limits


def my_limit(fn, lo, hi, rel=1e-7):
    """Largest k with fn(k) stable (fn(lo) stable, fn(hi) unstable assumed)."""
    while hi - lo > rel * hi:
        mid = 0.5 * (lo + hi)
        if fn(mid) <= 1 + TOL:
            lo = mid
        else:
            hi = mid
    return lo


# ---------------------------------------------------------------------------- search


class Found(Exception):
    pass


class Search:
    """Every evaluation goes through f(), which keeps the best point and every point above
    1 + 1e-8 (a find)."""

    def __init__(self, kc, bc, d, cls, rng, stop_on_find=False):
        self.kc, self.bc, self.d, self.cls = kc, bc, d, cls
        self.rng = rng
        self.best = (-math.inf, None, None)
        self.evals = 0
        self.finds = []
        self.suspects = []
        self.stop_on_find = stop_on_find

    def f(self, op, env):
        self.evals += 1
        try:
            r, status = objective_radius(self.kc, self.bc, op, env, self.d)
        except (np.linalg.LinAlgError, ValueError, OverflowError, ZeroDivisionError):
            return -1.0
        if not math.isfinite(r):
            r = 1e6
        if r > self.best[0]:
            self.best = (r, op, env)
        if status == "find":
            self.finds.append((r, op, env))
            if self.stop_on_find:
                raise Found()
        elif status == "suspect" and len(self.suspects) < 100000:
            self.suspects.append((spectral(self.kc, self.bc, op, env, self.d)[0], op, env))
        return r

    def verify(self, log, per_key=3, cap=24):
        """Re-check the largest finds and suspects (up to per_key for each environment kind
        and hands-on or off) in mpmath; only what mpmath confirms is a find. (Extreme
        two-mode environments put double-precision radii up to ~3e-4 off.)"""
        def pick(lst):
            count, out = {}, []
            for r, op, env in sorted(lst, key=lambda t: -t[0]):
                key = (op is None, env[0])
                if count.get(key, 0) >= per_key:
                    continue
                count[key] = count.get(key, 0) + 1
                out.append((r, op, env))
                if len(out) >= cap:
                    break
            return out
        confirmed = []
        noise = 0
        for label, lst in (("find", self.finds), ("suspect", self.suspects)):
            for r, op, env in pick(lst):
                lam, rmp = closed_loop_mp(self.kc, self.bc, op, env, self.d)
                rmp = float(rmp)
                ok = rmp > 1 + TOL
                if ok or noise < 3:
                    log("    mpmath re-check of a %s: double %.12f, mpmath %.15f -> %s  (%s, %s)"
                        % (label, r, rmp, "REAL" if ok else "rounding noise", fmt_op(op),
                           fmt_env(env)))
                noise += not ok
                if ok:
                    confirmed.append((rmp, op, env))
        log("    mpmath: %d confirmed, %d rounding noise" % (len(confirmed), noise))
        return confirmed

    @staticmethod
    def dims(kind):
        nop = 0 if kind[0] == "handsoff" else len(OP_KEYS)
        nenv = 0 if kind[1] == "wall" else len(ENV_BOX[kind[1]])
        return nop, nenv

    def split(self, kind, z):
        nop, _ = self.dims(kind)
        op = None if nop == 0 else op_from_u(z[:nop], self.cls)
        env = ("wall",) if kind[1] == "wall" else env_from_y(kind[1], z[nop:])
        return op, env

    def fz(self, kind, z):
        return self.f(*self.split(kind, np.clip(z, 0.0, 1.0)))

    def corners(self, envs):
        """Hands-off and every corner of the class box, against the wall and a grid of
        environments."""
        import itertools
        env_list = [("wall",)]
        if "implicit" in envs:
            for me in [0.0, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e5]:
                for ke in [0.0, 1.0, 1e3, 1e5, 1e7, 1e9]:
                    for be in [0.0, 1.0, 100.0]:
                        env_list.append(("implicit", me, ke, be))
        if "lossless" in envs:
            for lm in np.arange(-4, 7.01, 1.0):
                for lk in np.arange(-1, 11.01, 1.0):
                    env_list.append(("lossless", 10**lm, 10**lk))
        ops = [None] + list(dict.fromkeys(itertools.product(*[self.cls[k] for k in OP_KEYS])))
        for op in ops:
            for env in env_list:
                self.f(op, env)
        n = len(ops) * len(env_list)
        # hands-off: dense grids of the low-dimensional environment spaces
        for kind, pts in (("lossless", 90), ("implicit", 22), ("trapdamp", 15),
                          ("lossless2", 8)):
            if kind not in envs:
                continue
            dim = len(ENV_BOX[kind])
            g = np.linspace(0.0, 1.0, pts)
            for y in itertools.product(*([g] * dim)):
                self.f(None, env_from_y(kind, y))
                n += 1
        return n

    def z_of(self, kind, op, env):
        """The search coordinates of a point (for Nelder-Mead starts)."""
        z = []
        if kind[0] != "handsoff":
            z += [val_to_u(v, *self.cls[k]) for v, k in zip(op, OP_KEYS)]
        if kind[1] != "wall":
            for v, (lo, hi) in zip(env[1:], ENV_BOX[kind[1]]):
                if v <= 0:
                    z.append(0.0)
                else:
                    y = (math.log10(v) - lo) / (hi - lo)
                    if kind[1] == "implicit":
                        y = 0.02 + 0.98 * y
                    z.append(y)
        return np.clip(np.array(z, dtype=float), 0.0, 1.0)

    def run_kind(self, kind, cpu):
        """Differential evolution (restarted with new seeds) for ~55 % of cpu, then
        multi-start Nelder-Mead: from the best points DE met, then random starts."""
        dim = sum(self.dims(kind))
        best = (-math.inf, None, None)
        saved = self.best
        self.best = best
        t0 = time.process_time()
        if dim == 0:
            self.fz(kind, np.zeros(0))
        else:
            pop = max(8, 40 // dim)
            seed = int(self.rng.integers(1 << 30))
            elites = []
            while not elites or time.process_time() - t0 < 0.55 * cpu:
                res = scipy.optimize.differential_evolution(
                    lambda z: -self.fz(kind, z), [(0.0, 1.0)] * dim, maxiter=60,
                    popsize=pop, seed=seed, tol=0, atol=0, mutation=(0.5, 1.0),
                    recombination=0.7, polish=False, init="sobol")
                elites.append(np.array(res.x))
                seed += 1
            starts = elites[::-1]
            if self.best[2] is not None:
                starts.insert(0, self.z_of(kind, self.best[1], self.best[2]))
            while time.process_time() - t0 < cpu:
                z0 = starts.pop(0) if starts else self.rng.random(dim)
                scipy.optimize.minimize(lambda z: -self.fz(kind, z), z0, method="Nelder-Mead",
                                        options={"maxfev": 250 * dim, "xatol": 1e-10,
                                                 "fatol": 1e-14, "adaptive": True})
        kb = self.best
        if saved[0] > self.best[0]:
            self.best = saved
        return kb, time.process_time() - t0


def attack_case(kc, bc, d, cls, envs, budget, seed, log, stop_on_find=False):
    """Maximise the radius over the class x environments at (kc, bc, d): corners, then each
    (hands-off | hand) x environment kind, with CPU shared by dimension."""
    S = Search(kc, bc, d, cls, np.random.default_rng(seed), stop_on_find)
    t0 = time.process_time()
    per_kind = {}
    try:
        n = S.corners(envs)
        log("    corners: %d cases, best %.12f at %s, %s" % (
            n, S.best[0], fmt_op(S.best[1]), fmt_env(S.best[2])))
        per_kind["corners"] = S.best
        kinds = [(h, e) for e in envs for h in ("handsoff", "hand")]
        weights = [sum(Search.dims(k)) for k in kinds]
        for kind, w in zip(kinds, weights):
            kb, cpu = S.run_kind(kind, budget * w / sum(weights))
            per_kind["/".join(kind)] = kb
            log("    %-18s best %.12f at %s, %s (%.1f s)" % (
                "/".join(kind), kb[0], fmt_op(kb[1]), fmt_env(kb[2]), cpu))
    except Found:
        log("    stopped at the first find")
    confirmed = S.verify(log)
    return {"best": S.best, "per_kind": per_kind, "finds": confirmed, "evals": S.evals,
            "n_raw": len(S.finds), "n_suspect": len(S.suspects),
            "cpu": time.process_time() - t0}


def fmt_op(op):
    if op is None:
        return "hands-off"
    return "(m_h=%.6g, k_s=%.6g, b_s=%.6g, k_a=%.6g, b_a=%.6g)" % op


def fmt_env(env):
    if env is None:
        return "-"
    if env[0] == "wall":
        return "wall"
    return env[0] + "(" + ", ".join("%.6g" % v for v in env[1:]) + ")"


# ---------------------------------------------------------------------------- commands

CASES = [(bc, dp, scene) for dp in (0, 1) for bc in (0.0, 0.5, 1.0) for scene in (None, "wall")]


def cmd_validate(a):
    log = print
    # 1. hands-off device on a rigid wall, b_c = 0: the known limit ~ 2b/T = 4000 N/m.
    for d in (0, 1):
        for bc in (0.0, 0.5, 1.0):
            lim = my_limit(lambda k: spectral(k, bc, None, ("wall",), d)[0], 0.0, 1e5)
            log("hands-off, rigid wall, b_c = %.1f, delay %d T: k_c limit %.4f N/m" % (bc, d, lim))
    # 2. a hand-built check: a free mass (k_e = 0, b_e = 0 implicit) in free space (no force).
    rho = spectral(1000.0, 0.5, None, ("implicit", 0.0, 0.0, 0.0))
    log("hands-off, free space (implicit m=k=b=0), k_c=1000: rho=%.15f rest=%.6f free=%s"
        % rho)
    # 3. single-point classes vs the tool, rigid wall scene (the tool adds hands-off).
    rng = np.random.default_rng(1)
    pts = []
    for _ in range(a.n):
        op = tuple(u_to_val(u, *CLASS[k]) for u, k in zip(rng.random(5), OP_KEYS))
        kc = float(rng.uniform(500, 9000))
        bc = float(rng.choice([0.0, 0.5, 1.0, 2.0]))
        d = int(rng.choice([0, 1]))
        pts.append((op, kc, bc, d))
    pts.append(((0.1, 0.0, 2.0, 0.0, 0.0), 4010.0, 0.0, 0))
    pts.append(((2.0, 3000.0, 30.0, 1000.0, 20.0), 1339.0, 0.0, 1))
    worst = 0.0
    agree = 0
    for i, (op, kc, bc, d) in enumerate(pts):
        f = write_point_class("build/class-adversary/validate-%d.toml" % i, op)
        rc, js, err = tool_check(a.tool, kc, bc, d * T, f, WALL_SCENE)
        own = max(spectral(kc, bc, op, ("wall",), d)[0], spectral(kc, bc, None, ("wall",), d)[0])
        tr = js.get("worst_spectral_radius") if js else None
        ok_own = own <= 1 + TOL
        ok_tool = rc == 0
        agree += ok_own == ok_tool
        diff = abs(own - tr) if tr is not None else float("nan")
        worst = max(worst, diff if math.isfinite(diff) else 0)
        log("  %2d kc=%7.1f bc=%.1f d=%d %s: own %.12f (%s), tool %s %s, diff %.2e" % (
            i, kc, bc, d, fmt_op(op), own, "stable" if ok_own else "UNSTABLE",
            "%.12f" % tr if tr is not None else None, "stable" if ok_tool else "UNSTABLE",
            diff))
    log("wall scene: verdicts agree on %d/%d; largest |radius difference| %.3e"
        % (agree, len(pts), worst))
    # 4. a virtual-mass scene: the implicit mass-spring (0.5 kg, 20 N/m, 1 N s/m)
    vm = "config/scenes/virtual-mass.toml"
    agree = 0
    for i, (op, kc, bc, d) in enumerate(pts[:8]):
        f = "build/class-adversary/validate-%d.toml" % i
        rc, js, err = tool_check(a.tool, kc, bc, d * T, f, vm)
        env = ("implicit", 0.5, 20.0, 1.0)
        own = max(spectral(kc, bc, op, env, d)[0], spectral(kc, bc, None, env, d)[0])
        tr = js.get("worst_spectral_radius") if js else None
        log("  vm %2d kc=%7.1f bc=%.1f d=%d: own %.12f, tool %s (%s; worst env %s)" % (
            i, kc, bc, d, own, tr, "stable" if rc == 0 else "UNSTABLE",
            js.get("worst_environment") if js else err.strip()))
        agree += (own <= 1 + TOL) == (rc == 0)
    log("virtual-mass scene: verdicts agree on %d/8" % agree)
    # 5. the counterexamples (see the module docstring): hands-off on a lossless trapezoidal
    # mass, one period of delay, below the tool's class limit. Double, mpmath, a time-domain
    # run, and the tool's verdict for the class (hands-off belongs to every class).
    # The last two are against the fixed tool (snapshot2): at its own size limit (b_c = 0.5)
    # and at the top of its check's window (b_c = 0), a free lossless mass; rejected from
    # ~1e-5 above the limit, accepted below. (Their radii are ~1 + 5e-6: the time-domain run
    # needs 5e5 ticks to outlast the slow real mode the weak k_e leaves near z = 1.)
    for kc, bc, me, ke in ((1053.3008, 0.0, 0.10651, 0.01), (1010.0, 0.0, 0.1, 0.01),
                           (1618.8184, 0.5, 0.421465, 0.01), (1617.1875, 0.5, 0.420484, 0.01),
                           (1007.4293, 0.0, 0.101682, 0.01)):
        env = ("lossless", me, ke)
        rho = spectral(kc, bc, None, env, 1)[0]
        rmp = float(closed_loop_mp(kc, bc, None, env, 1)[1])
        g = simulate_lossless(kc, bc, None, me, ke, 1, ticks=60000 if rho > 1 + 1e-5 else 500000)
        rc, js, err = tool_check(a.tool, kc, bc, T, a.cls)
        log("counterexample k_c=%.4f b_c=%.1f delay 1T, hands-off, lossless(m_e=%g, k_e=%g): "
            "radius %.12f (mpmath %.12f, time-domain growth %.9f/tick); tool --operator-class "
            "%s: %s (its worst radius %s)" % (kc, bc, me, ke, rho, rmp, g, a.cls,
                                               {0: "stable", 1: "UNSTABLE"}.get(rc, rc),
                                               js and js.get("worst_spectral_radius")))


def get_limits(a, cls_file):
    """The tool's class limits for the 12 cases (cached in build/class-adversary/, keyed by
    the tool's and the class file's modification times)."""
    key = "%s|%s|%s|%s" % (a.tool, os.path.getmtime(a.tool), cls_file,
                           os.path.getmtime(cls_file))
    cache = "build/class-adversary/limits.json"
    try:
        with open(cache) as f:
            c = json.load(f)
        if c["key"] == key:
            return {(r["b_c"], r["dp"], r["scene"]): r["js"] for r in c["rows"]}
    except (OSError, ValueError, KeyError):
        pass
    out = {}
    for bc, dp, scene in CASES:
        js = tool_size(a.tool, bc, dp * T, cls_file, WALL_SCENE if scene else None)
        out[(bc, dp, scene)] = js
    os.makedirs(os.path.dirname(cache), exist_ok=True)
    with open(cache, "w") as f:
        json.dump({"key": key, "rows": [{"b_c": k[0], "dp": k[1], "scene": k[2], "js": v}
                                        for k, v in out.items()]}, f, indent=1)
    return out


def cmd_limits(a):
    lim = get_limits(a, a.cls)
    print("| b_c | delay | environments | tool size k_c | rejected | tool's worst case |")
    print("|---|---|---|---|---|---|")
    for (bc, dp, scene), js in lim.items():
        print("| %.1f | %d T | %s | %.4f | %.4f | %s / %s |" % (
            bc, dp, "rigid wall" if scene else "all passive", js["stiffness"],
            js["rejected_stiffness"], js["worst_operator"], js["worst_environment"]))


def cmd_attack(a):
    cls = parse_class(a.cls)
    for k in OP_KEYS:
        cls.setdefault(k, CLASS[k])
    log = lambda s: (print(s), sys.stdout.flush())
    t_all = time.process_time()
    lim = get_limits(a, a.cls)
    todo = CASES if a.cases is None else [CASES[int(i)] for i in a.cases.split(",")]
    results = []
    for bc, dp, scene in todo:
        js = lim[(bc, dp, scene)]
        k_lim = js["stiffness"]
        envs = ["wall"] if scene else ["wall", "implicit", "lossless"] + (
            ["lossless2", "trapdamp"] if a.extra else [])
        for factor in a.factors:
            kc = factor * k_lim
            log("case b_c=%.1f delay=%dT %s: tool limit %.4f, attacking k_c = %.4f (x%.3f)" % (
                bc, dp, "wall only" if scene else "all environments", k_lim, kc, factor))
            r = attack_case(kc, bc, dp, cls, envs, a.budget * (0.5 if factor > 1 else 1.0),
                            a.seed, log, stop_on_find=factor > 1)
            best = r["best"]
            row = {"b_c": bc, "delay_periods": dp, "scene": "wall" if scene else None,
                   "tool_limit": k_lim, "factor": factor, "k_c": kc,
                   "best_radius": best[0], "best_op": best[1], "best_env": best[2],
                   "evals": r["evals"], "cpu_s": r["cpu"], "n_finds": len(r["finds"])}
            log("  -> best objective %.12f at %s, %s; %d evals, %.1f s CPU; %d points > 1+1e-8 "
                "away from z = 1, %d near z = 1 (suspects); %d confirmed in mpmath"
                % (best[0], fmt_op(best[1]), fmt_env(best[2]), r["evals"], r["cpu"],
                   r["n_raw"], r["n_suspect"], len(r["finds"])))
            if r["finds"]:
                # confirm the worst find with the tool, at this point as a single-point class
                rr, op, env = max(r["finds"], key=lambda t: t[0])
                rho_full = (rr,)
                row["find"] = {"radius": rr, "op": op, "env": env}
                if op is not None:
                    f = write_point_class("build/class-adversary/find-bc%.1f-d%d-%s-x%.3f.toml" % (
                        bc, dp, "wall" if scene else "all", factor), op)
                else:
                    f = a.cls  # hands-off belongs to every class
                rc, tj, err = tool_check(a.tool, kc, bc, dp * T, f, WALL_SCENE if scene else None)
                row["find"]["class_file"] = f
                row["find"]["tool_check_rc"] = rc
                row["find"]["tool_radius"] = tj and tj.get("worst_spectral_radius")
                log("  find: %s, %s, radius %.12f; tool check --operator-class %s: %s, "
                    "radius %s at %s / %s" % (
                        fmt_op(op), fmt_env(env), rho_full[0], f,
                        {0: "stable", 1: "UNSTABLE"}.get(rc, "rc=%d" % rc),
                        tj and tj.get("worst_spectral_radius"), tj and tj.get("worst_operator"),
                        tj and tj.get("worst_environment")))
            results.append(row)
    ch = os.times()
    log("total CPU %.1f s (this process), %.1f s (the tool's runs)" % (
        time.process_time() - t_all, ch.children_user + ch.children_system))
    if a.out:
        with open(a.out, "w") as f:
            json.dump(results, f, indent=1, default=str)


def crit_k(bc, op, env, d, k_hi, k_lo):
    """Bisection on k_c for one configuration: stable at k_lo, unstable at k_hi."""
    f = lambda k: objective_radius(k, bc, op, env, d)[0]
    if f(k_lo) > 1 + TOL:
        return k_lo
    while k_hi - k_lo > 1e-6 * k_hi:
        mid = 0.5 * (k_lo + k_hi)
        if f(mid) > 1 + TOL:
            k_hi = mid
        else:
            k_lo = mid
    return k_hi


def polish(bc, dp, cls, op, env, kc, k_lo, rounds=3):
    """Tighten a limit below the focused search's 2e-4 step: Nelder-Mead on the worst
    configuration's own coordinates at its critical k_c (it is unstable there), then that
    configuration's critical k_c again; repeat while it drops."""
    kind = ("handsoff" if op is None else "hand", env[0])
    for _ in range(rounds):
        S = Search(kc, bc, dp, cls, np.random.default_rng(0))
        z0 = S.z_of(kind, op, env)
        if not len(z0):
            break
        r = scipy.optimize.minimize(lambda z: -S.fz(kind, z), z0, method="Nelder-Mead",
                                    options={"maxfev": 600 * len(z0), "xatol": 1e-12,
                                             "fatol": 1e-15, "adaptive": True})
        op2, env2 = S.split(kind, np.clip(r.x, 0.0, 1.0))
        k2 = crit_k(bc, op2, env2, dp, kc, k_lo)
        if k2 >= kc * (1 - 1e-7):
            break
        kc, op, env = k2, op2, env2
    return kc, op, env


def cmd_window(a):
    """Where the tool's own `check --operator-class` verdict flips, against the adversary's limit
    (own-limits' output): bisection on the tool's check between the adversary's limit and the tool's
    rejected stiffness. A flip above the adversary's limit means check accepts gains that are unstable
    for a member of the class (the configuration own-limits names)."""
    with open(a.own_limits) as f:
        rows = json.load(f)
    lim = get_limits(a, a.cls)
    log = lambda s: (print(s), sys.stdout.flush())
    for r in rows:
        bc, dp, scene = r["b_c"], r["delay_periods"], r["scene"]
        own = r["own"]
        js = lim[(bc, dp, scene)]
        sc = WALL_SCENE if scene else None
        ok = lambda k: tool_check(a.tool, k, bc, dp * T, a.cls, sc)[0] == 0
        lo, hi = own, js["rejected_stiffness"]
        if not ok(lo):
            log("b_c=%.1f d=%dT %-11s own %.4f: the tool's check already rejects the adversary's limit"
                % (bc, dp, "wall" if scene else "all passive", own))
            continue
        while hi - lo > 2e-5 * hi:
            mid = 0.5 * (lo + hi)
            if ok(mid):
                lo = mid
            else:
                hi = mid
        op = None if r["op"] is None else tuple(r["op"])
        env = tuple(r["env"]) if isinstance(r["env"], list) else r["env"]
        rho = float(closed_loop_mp(lo, bc, op, env, dp)[1])
        log("b_c=%.1f d=%dT %-11s own %.4f  tool size %.4f  tool check accepts up to %.4f "
            "(%.4f %% above own; there %s, %s has radius %.9f)" % (
                bc, dp, "wall" if scene else "all passive", own, js["stiffness"], lo,
                100 * (lo / own - 1), fmt_op(op), fmt_env(env), rho))


def cmd_own_limits(a):
    """My own class limit for each case: start from a find at 1.01 x the tool's limit; the
    configuration's own critical k_c (bisection); a focused search just below it (corners,
    grids, every kind, Nelder-Mead from the configuration); repeat while that finds more."""
    cls = parse_class(a.cls)
    for k in OP_KEYS:
        cls.setdefault(k, CLASS[k])
    log = lambda s: (print(s), sys.stdout.flush())
    lim = get_limits(a, a.cls)
    todo = CASES if a.cases is None else [CASES[int(i)] for i in a.cases.split(",")]
    rows = []
    t_all = time.process_time()
    for bc, dp, scene in todo:
        t0 = time.process_time()
        k_tool = lim[(bc, dp, scene)]["stiffness"]
        envs = ["wall"] if scene else ["wall", "implicit", "lossless"]
        k = 1.01 * k_tool
        r = attack_case(k, bc, dp, cls, envs, 2.0, a.seed, lambda s: None, stop_on_find=True)
        if not r["finds"]:
            log("b_c=%.1f d=%dT %s: nothing at 1.01 x the tool's limit" % (bc, dp, scene))
            continue
        _, op, env = r["finds"][0]
        for it in range(6):
            kc = crit_k(bc, op, env, dp, k, 0.5 * k_tool)
            probe = kc * (1 - 2e-4)
            S = Search(probe, bc, dp, cls, np.random.default_rng(a.seed + it), True)
            found = None
            try:
                kind = ("handsoff" if op is None else "hand", env[0])
                S.f(op, env)
                S.corners(envs)
                z0 = S.z_of(kind, op, env)
                if len(z0):
                    scipy.optimize.minimize(lambda z: -S.fz(kind, z), z0, method="Nelder-Mead",
                                            options={"maxfev": 400 * len(z0),
                                                     "adaptive": True})
                for kd in [(h, e) for e in envs for h in ("handsoff", "hand")]:
                    S.run_kind(kd, a.budget * sum(Search.dims(kd)) / 25.0)
            except Found:
                found = S.finds[-1]
            if found is not None:
                lam, rmp = closed_loop_mp(probe, bc, found[1], found[2], dp)
                if float(rmp) <= 1 + TOL:
                    found = None
            if found is None:
                break
            _, op, env = found
            k = probe
        kc, op, env = polish(bc, dp, cls, op, env, kc, 0.5 * k_tool)
        row = {"b_c": bc, "delay_periods": dp, "scene": scene, "tool": k_tool, "own": kc,
               "op": op, "env": env, "ratio": kc / k_tool}
        rows.append(row)
        log("b_c=%.1f d=%dT %-11s tool %.4f  own %.4f  (own/tool %.5f) worst %s, %s  "
            "[%.1f s]" % (bc, dp, "wall" if scene else "all passive", k_tool, kc, kc / k_tool,
                          fmt_op(op), fmt_env(env), time.process_time() - t0))
    log("total CPU %.1f s" % (time.process_time() - t_all))
    if a.out:
        with open(a.out, "w") as f:
            json.dump(rows, f, indent=1, default=str)


def cmd_point(a):
    op = None if a.op is None else tuple(float(x) for x in a.op.split(","))
    e = a.env.split(",")
    env = (e[0], *[float(x) for x in e[1:]])
    print(spectral(a.kc, a.bc, op, env, a.delay_periods))


# CI's quick mode: (b_c, delay in periods, scene) per class file, every verdict kind a class
# can certify (every passive environment, a scene with it, no delay and one period).
QUICK_CASES = [(0.5, 0, None), (1.0, 1, None), (0.5, 0, "wall")]


def cmd_quick(a):
    """Attack the tool's proven class limits just below them (--factor, 0.999 by default) for
    a few CPU seconds each; exit 1 when any find survives the mpmath re-check. What was
    tried, and the closest it came, is printed per case."""
    cls = parse_class(a.cls)
    for k in OP_KEYS:
        if k not in cls:
            raise SystemExit("%s: [operator] %s missing" % (a.cls, k))
    log = lambda s: (print(s), sys.stdout.flush())
    failures = 0
    t_all = time.process_time()
    for bc, dp, scene in QUICK_CASES:
        js = tool_size(a.tool, bc, dp * T, a.cls, WALL_SCENE if scene else None)
        kc = a.factor * js["stiffness"]
        envs = ["wall"] if scene else ["wall", "implicit", "lossless"]
        log("case %s, b_c = %.2f, delay %d T, %s: the tool proves %.4f N/m (%s); attacking "
            "%.4f (x%.4f) over the class x %s for %.1f s CPU" % (
                a.cls, bc, dp, "the rigid-wall scene" if scene else "every passive environment",
                js["stiffness"], js.get("proof", "?"), kc, a.factor, "/".join(envs), a.budget))
        r = attack_case(kc, bc, dp, cls, envs, a.budget, a.seed, log)
        best = r["best"]
        log("  -> %d configurations, closest: radius %.12f at %s, %s; %d confirmed finds" % (
            r["evals"], best[0], fmt_op(best[1]), fmt_env(best[2]), len(r["finds"])))
        for rr, op, env in r["finds"]:
            failures += 1
            log("  BROKEN: %s, %s grows by %.12f per tick at %.4f x the proven limit" % (
                fmt_op(op), fmt_env(env), rr, a.factor))
    log("quick attack: %d cases, %d broken, %.1f s CPU" % (
        len(QUICK_CASES), failures, time.process_time() - t_all))
    sys.exit(1 if failures else 0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--tool", default=TOOL)
    p.add_argument("--cls", default=CLASS_FILE)
    sp = p.add_subparsers(dest="cmd", required=True)
    v = sp.add_parser("validate")
    v.add_argument("--n", type=int, default=14)
    sp.add_parser("limits")
    w = sp.add_parser("window")
    w.add_argument("--own-limits", default="build/class-adversary/own-limits.json")
    ml = sp.add_parser("own-limits")
    ml.add_argument("--budget", type=float, default=4.0, help="CPU seconds per probe")
    ml.add_argument("--cases", default=None)
    ml.add_argument("--seed", type=int, default=0)
    ml.add_argument("--out", default=None)
    at = sp.add_parser("attack")
    at.add_argument("--factors", type=lambda s: [float(x) for x in s.split(",")],
                    default=[0.995])
    at.add_argument("--budget", type=float, default=30.0, help="CPU seconds per case")
    at.add_argument("--cases", default=None, help="indices into the 12 cases, comma-separated")
    at.add_argument("--seed", type=int, default=0)
    at.add_argument("--extra", action="store_true",
                    help="also a two-mode lossless environment (mass-spring + resonator) and "
                         "a lossy trapezoidal mass-spring-damper (beyond the brief)")
    at.add_argument("--out", default=None)
    qk = sp.add_parser("quick")
    qk.add_argument("--factor", type=float, default=0.999)
    qk.add_argument("--budget", type=float, default=2.0, help="CPU seconds per case")
    qk.add_argument("--seed", type=int, default=0)
    pt = sp.add_parser("point")
    pt.add_argument("--kc", type=float, required=True)
    pt.add_argument("--bc", type=float, default=0.0)
    pt.add_argument("--delay-periods", type=int, default=0)
    pt.add_argument("--op", default=None, help="m_h,k_s,b_s,k_a,b_a (omit: hands-off)")
    pt.add_argument("--env", default="wall", help="wall | implicit,me,ke,be | lossless,me,ke")
    a = p.parse_args()
    if a.cmd != "point" and not os.access(a.tool, os.X_OK):
        print("class_adversary.py: --tool %s is not an executable haptic-tune (build it: "
              "cmake --preset release && cmake --build --preset release)" % a.tool, file=sys.stderr)
        sys.exit(2)
    if not os.path.isfile(a.cls):
        print("class_adversary.py: --cls %s: no such class file (run from the repository's "
              "root)" % a.cls, file=sys.stderr)
        sys.exit(2)
    {"validate": cmd_validate, "limits": cmd_limits, "attack": cmd_attack,
     "own-limits": cmd_own_limits, "point": cmd_point, "window": cmd_window,
     "quick": cmd_quick}[a.cmd](a)


if __name__ == "__main__":
    main()
