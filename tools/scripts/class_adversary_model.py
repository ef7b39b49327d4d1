"""The independent model behind class_adversary.py: the closed loop of device, coupling,
operator and environment built from numpy and scipy (not the project's C++), its spectral
radius in double and mpmath precision, a lossless simulation, and the coordinates the
searches move in. class_adversary.py has the searches and the commands."""
import math

import numpy as np
import scipy.linalg

M_DEV = 0.1
B_DEV = 2.0
T = 1e-3
TOL = 1e-8
OP_KEYS = ["hand_mass", "grip_stiffness", "grip_damping", "arm_stiffness", "arm_damping"]


# ---------------------------------------------------------------------------- the class


def parse_class(path):
    """A minimal reader for the [operator] table (numbers or [min, max])."""
    out = {}
    section = None
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            if line.startswith("["):
                section = line.strip("[]").strip()
                continue
            if section != "operator" or "=" not in line:
                continue
            k, v = [s.strip() for s in line.split("=", 1)]
            if v.startswith("["):
                lo, hi = [float(s) for s in v.strip("[]").split(",")]
            else:
                lo = hi = float(v)
            out[k] = (lo, hi)
    return out


# ---------------------------------------------------------------------------- the model

_zoh_cache = {}


def plant_zoh(op, m=M_DEV, b=B_DEV, T=T):
    """Exact ZOH sampling of the device (+ hand). op None = hands-off, else
    (m_h, k_s, b_s, k_a, b_a). State [x, v] or [x, v, x_h, v_h]; input F (the coupling
    force, opposing the handle)."""
    key = (op, m, b, T)
    if key in _zoh_cache:
        return _zoh_cache[key]
    if op is None:
        A = np.array([[0.0, 1.0], [0.0, -b / m]])
        Bm = np.array([[0.0], [-1.0 / m]])
    else:
        mh, ks, bs, ka, ba = op
        A = np.array([
            [0.0, 1.0, 0.0, 0.0],
            [-ks / m, -(b + bs) / m, ks / m, bs / m],
            [0.0, 0.0, 0.0, 1.0],
            [ks / mh, bs / mh, -(ks + ka) / mh, -(bs + ba) / mh],
        ])
        Bm = np.array([[0.0], [-1.0 / m], [0.0], [0.0]])
    n = A.shape[0]
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = A * T
    aug[:n, n:] = Bm * T
    E = scipy.linalg.expm(aug)
    res = (E[:n, :n], E[:n, n])
    if len(_zoh_cache) > 4096:
        _zoh_cache.clear()
    _zoh_cache[key] = res
    return res


def polymul(p, q):
    """Polynomial product (works for float and mpmath object arrays)."""
    out = [0 * p[0] * q[0]] * (len(p) + len(q) - 1)
    for i, a in enumerate(p):
        for j, c in enumerate(q):
            out[i + j] = out[i + j] + a * c
    return np.array(out)


def env_tf(env, T=T):
    """The environment as F = N(z^-1)/D(z^-1) x_e, coefficients in powers of z^-1
    (D[0] = 1). None for the rigid wall."""
    kind = env[0]
    if kind == "wall":
        return None
    if kind == "implicit":
        _, me, ke, be = env
        N = np.array([me / T**2 + be / T + ke, -2 * me / T**2 - be / T, me / T**2])
        return N, np.array([1.0])
    if kind == "lossless":
        _, me, ke = env
        # (m_e s + k_e/s) s_b = [2 m_e/T^2 (1 - z^-1)^2 + k_e/2 (1 + z^-1)^2] / (1 + z^-1)
        if me == 0.0:
            return np.array([ke / 2, ke / 2]), np.array([1.0])
        N = 2 * me / T**2 * np.array([1.0, -2.0, 1.0]) + ke / 2 * np.array([1.0, 2.0, 1.0])
        return N, np.array([1.0, 1.0])
    if kind == "lossless2":
        # m_e s + k_e/s + k_r s/(s^2 + k_r/M_r): a mass-spring plus a resonator (a mass M_r
        # hung off the contact point on a spring k_r), all trapezoidal: a two-mode Foster form
        _, me, ke, kr, Mr = env
        q1m = np.array([1.0, -1.0])
        q1p = np.array([1.0, 1.0])
        sq = polymul
        N1 = 2 * me / T**2 * sq(q1m, q1m) + ke / 2 * sq(q1p, q1p)
        D2 = 4 / T**2 * sq(q1m, q1m) + kr / Mr * sq(q1p, q1p)
        N = sq(N1, D2) + 2 * kr / T**2 * sq(sq(q1m, q1m), sq(q1p, q1p))
        D = sq(q1p, D2)
        return N / D[0], D / D[0]
    if kind == "trapdamp":
        # a lossy trapezoidal mass-spring-damper: m_e s + b_e + k_e/s
        _, me, ke, be = env
        N = (2 * me / T**2 * np.array([1.0, -2.0, 1.0]) + ke / 2 * np.array([1.0, 2.0, 1.0])
             + be / T * np.array([1.0, 0.0, -1.0]))
        return N, np.array([1.0, 1.0])
    raise ValueError(kind)


def env_anchored(env):
    kind = env[0]
    if kind == "wall":
        return True
    if kind == "implicit":
        return env[2] > 0
    if kind == "lossless":
        return env[2] > 0
    if kind in ("lossless2", "trapdamp"):
        return env[2] > 0
    raise ValueError(kind)


def closed_loop(kc, bc, op, env, d=0, m=M_DEV, b=B_DEV, T=T):
    """The closed-loop transition matrix. State: plant (np), x_d[n-1], x_e[n-1..n-q],
    F[n-1..n-r]."""
    Ad, Bd = plant_zoh(op, m, b, T)
    return _assemble(kc, bc, Ad, Bd, env_tf(env, T), d, T, np.zeros)


def _assemble(kc, bc, Ad, Bd, tf, d, T, zeros):
    npl = Ad.shape[0]
    if tf is None:
        q, nr_env = 0, 0
    else:
        N, D = tf
        q = max(len(N) - 1, 1)
        nr_env = len(D) - 1
    r = max(d, nr_env)
    n = npl + 1 + q + r
    ixd = npl
    ixe = npl + 1
    iF = npl + 1 + q
    # Lc: F = Lc.S - (k_c + b_c/T) x_e[n]
    Lc = zeros(n)
    Lc[0] += kc + bc / T
    Lc[ixd] -= bc / T
    if tf is None:
        Frow = Lc
        xerow = None
    else:
        Lc[ixe] += bc / T
        # Lh: F = N0 x_e[n] + Lh.S
        Lh = zeros(n)
        for i in range(1, len(N)):
            Lh[ixe + i - 1] += N[i]
        for i in range(1, len(D)):
            Lh[iF + i - 1] -= D[i]
        xerow = (Lc - Lh) / (N[0] + kc + bc / T)
        Frow = Lc - (kc + bc / T) * xerow
    Phi = np.array([zeros(n) for _ in range(n)])
    Phi[:npl, :npl] = Ad
    if d == 0:
        Fapp = Frow
    else:
        Fapp = zeros(n)
        Fapp[iF + d - 1] += 1
    Phi[:npl, :] += np.outer(Bd, Fapp)
    Phi[ixd, 0] += 1
    if q:
        Phi[ixe] = xerow
        for i in range(1, q):
            Phi[ixe + i, ixe + i - 1] += 1
    if r:
        Phi[iF] = Frow
        for i in range(1, r):
            Phi[iF + i, iF + i - 1] += 1
    return Phi


def closed_loop_mp(kc, bc, op, env, d=0, dps=50):
    """The same closed loop in mpmath at dps digits: the device, the hand, T and every
    coefficient exact to dps digits, and the eigenvalues. Verifies finds whose eigenvalue
    is within reach of double-precision rounding (a near-defective pair at z = 1)."""
    import mpmath as mp
    mp.mp.dps = dps
    mpf = mp.mpf
    Tm, mm, bm = mpf(1) / 1000, mpf(1) / 10, mpf(2)
    kc, bc = mpf(kc), mpf(bc)
    if op is None:
        A = mp.matrix([[0, 1], [0, -bm / mm]])
        Bm = mp.matrix([[0], [-1 / mm]])
    else:
        mh, ks, bs, ka, ba = [mpf(x) for x in op]
        A = mp.matrix([
            [0, 1, 0, 0],
            [-ks / mm, -(bm + bs) / mm, ks / mm, bs / mm],
            [0, 0, 0, 1],
            [ks / mh, bs / mh, -(ks + ka) / mh, -(bs + ba) / mh],
        ])
        Bm = mp.matrix([[0], [-1 / mm], [0], [0]])
    npl = A.rows
    aug = mp.zeros(npl + 1, npl + 1)
    for i in range(npl):
        for j in range(npl):
            aug[i, j] = A[i, j] * Tm
        aug[i, npl] = Bm[i, 0] * Tm
    E = mp.expm(aug)
    Ad = np.array([[E[i, j] for j in range(npl)] for i in range(npl)], dtype=object)
    Bd = np.array([E[i, npl] for i in range(npl)], dtype=object)
    envm = (env[0], *[mpf(x) for x in env[1:]])
    tf = env_tf(envm, Tm)
    Phi = _assemble(kc, bc, Ad, Bd, tf, d, Tm, lambda n: np.array([mpf(0)] * n, dtype=object))
    n = Phi.shape[0]
    lam = mp.eig(mp.matrix(Phi.tolist()), left=False, right=False)
    return [complex(x) for x in lam], max(abs(x) for x in lam)


def simulate_lossless(kc, bc, op, me, ke, d, ticks=60000, seed=3):
    """A time-domain cross-check, written separately from closed_loop: step the loop tick
    by tick (the exact ZOH plant; the trapezoidal mass and spring as their own recursions
    F_m[n] = -F_m[n-1] + (2 m_e/T)(v_e[n] - v_e[n-1]),
    F_k[n] = F_k[n-1] + (k_e T/2)(v_e[n] + v_e[n-1]);
    the coupling solved for v_e[n]; a FIFO of forces for the delay) and return the growth
    per tick of the state's norm over the second half of the run."""
    Ad, Bd = plant_zoh(op)
    rng = np.random.default_rng(seed)
    p = rng.standard_normal(Ad.shape[0]) * 1e-3
    xd_prev, xe, ve, Fm, Fk = 0.0, 0.0, 0.0, 0.0, 0.0
    fifo = [0.0] * d
    a = 2 * me / T + ke * T / 2
    norms = []
    peak = 0.0
    for n in range(ticks):
        x = p[0]
        vd = (x - xd_prev) / T
        # F = a v_e + c (environment) = k_c (x - xe - T v_e) + b_c (vd - v_e) (coupling)
        c = -Fm - 2 * me / T * ve + Fk + ke * T / 2 * ve
        v_new = (kc * (x - xe) + bc * vd - c) / (a + kc * T + bc)
        F = a * v_new + c
        Fm = -Fm + 2 * me / T * (v_new - ve)
        Fk = Fk + ke * T / 2 * (v_new + ve)
        xe += T * v_new
        ve = v_new
        xd_prev = x
        fifo.append(F)
        Fapp = fifo.pop(0)
        p = Ad @ p + Bd * Fapp
        peak = max(peak, abs(p[0]), abs(F) / 1e3)  # the block's peak, free of the phase
        if n % 1000 == 999:
            norms.append(math.log(max(peak, 1e-300)))
            peak = 0.0
    h = len(norms) // 2
    return math.exp((norms[-1] - norms[h]) / ((len(norms) - 1 - h) * 1000))


def free_modes(op, env):
    """How many eigenvalues sit at exactly z = 1: spring-connected groups of masses that
    nothing ties to ground (the coupling k_c always ties device and environment)."""
    n = 0
    hand_to_dev = op is not None and op[1] > 0
    hand_to_gnd = op is not None and op[3] > 0
    if op is not None and not hand_to_dev and not hand_to_gnd:
        n += 1  # the hand alone, tied by dampers only
    if not (env_anchored(env) or (hand_to_dev and hand_to_gnd)):
        n += 1  # the device and the environment
    return n


def spectral(kc, bc, op, env, d=0):
    """(spectral radius, radius without the free z = 1 modes, the free-mode eigenvalues)."""
    Phi = closed_loop(kc, bc, op, env, d)
    if not np.all(np.isfinite(Phi)):
        return math.inf, math.inf, []
    lam = np.linalg.eigvals(Phi)
    a = np.abs(lam)
    rho = float(a.max())
    nf = free_modes(op, env)
    idx = list(np.argsort(np.abs(lam - 1.0))[:nf])
    rest = np.delete(a, idx)
    return rho, float(rest.max()) if rest.size else 0.0, [complex(lam[i]) for i in idx]


NEAR_ONE = 2e-3  # eigenvalues this close to z = 1 (below ~0.3 Hz) do not guide the search


def objective_radius(kc, bc, op, env, d=0):
    """What the search maximises, and whether the point is a find. A free or weakly
    anchored position (k_s, k_a, k_e -> 0) leaves an eigenvalue at or just below z = 1
    whatever else happens, which would make the landscape flat at 1; so the objective is the
    largest |z| among the eigenvalues farther than NEAR_ONE from 1. Returns
    (objective, status): status "find" when an eigenvalue away from 1 exceeds 1 + 1e-8,
    "suspect" when only one within NEAR_ONE of 1 does (a near-defective pair at z = 1,
    e.g. a free 1e5 kg virtual mass, puts double-precision eigenvalues ~1e-8 off: these are
    re-checked in mpmath, closed_loop_mp), else "ok"."""
    Phi = closed_loop(kc, bc, op, env, d)
    if not np.all(np.isfinite(Phi)):
        return math.inf, "find"
    lam = np.linalg.eigvals(Phi)
    a = np.abs(lam)
    near = np.abs(lam - 1.0) <= NEAR_ONE
    far = a[~near]
    obj = float(far.max()) if far.size else 0.0
    if obj > 1 + TOL:
        return obj, "find"
    if a.max() > 1 + TOL:
        return obj, "suspect"
    return obj, "ok"


# ---------------------------------------------------------------------------- coordinates

ALPHA = math.log(1e6)  # resolution near the low end: ~ (hi - lo) * 1e-6


def u_to_val(u, lo, hi):
    """u in [0, 1] -> [lo, hi], log-like: lo reached exactly at u = 0, hi at u = 1."""
    u = min(max(u, 0.0), 1.0)
    if hi <= lo:
        return lo
    if lo > 0:  # a true log scale
        return lo * (hi / lo) ** u
    return lo + (hi - lo) * (math.expm1(ALPHA * u) / math.expm1(ALPHA))


def val_to_u(v, lo, hi):
    if hi <= lo:
        return 0.0
    if lo > 0:
        return math.log(v / lo) / math.log(hi / lo)
    return math.log1p((v - lo) / (hi - lo) * math.expm1(ALPHA)) / ALPHA


def op_from_u(u, cls):
    return tuple(u_to_val(ui, *cls[k]) for ui, k in zip(u, OP_KEYS))


# Environment boxes, in log10 (wide).
ENV_BOX = {
    # implicit Euler mass-spring-damper: m_e, k_e, b_e (log10); each may also be 0
    "implicit": [(-4.0, 6.0), (-2.0, 10.0), (-3.0, 5.0)],
    # lossless trapezoidal mass-spring: m_e, k_e
    "lossless": [(-5.0, 7.0), (-2.0, 11.0)],
    # mass-spring + resonator: m_e, k_e, k_r, M_r
    # (narrower than lossless: at 1e-5 kg with 1e11 N/m double precision is ~3e-4 off)
    "lossless2": [(-4.0, 6.0), (-2.0, 9.0), (-2.0, 9.0), (-4.0, 6.0)],
    # trapezoidal mass-spring-damper: m_e, k_e, b_e
    "trapdamp": [(-5.0, 7.0), (-2.0, 11.0), (-3.0, 5.0)],
}


def env_from_y(kind, y):
    """y in [0, 1]^k -> the environment; for implicit, y < 0.02 means exactly 0."""
    box = ENV_BOX[kind]
    vals = []
    for yi, (lo, hi) in zip(y, box):
        yi = min(max(yi, 0.0), 1.0)
        if kind == "implicit" and yi < 0.02:
            vals.append(0.0)
        else:
            if kind == "implicit":
                yi = (yi - 0.02) / 0.98
            vals.append(10 ** (lo + (hi - lo) * yi))
    return (kind, *vals)
