#!/usr/bin/python3
"""
Independent lifted-operator reference for the sampled-data passivity bound
b*(controller, D) of a 1-DOF haptic device

    m dv/dt = F_h - b v - F_d,   F_d(t) = F[n] on [nT+D, (n+1)T+D),  D=(q+phi)T

Port (v in, F_h out) passive  <=>  int v (b v + F_d) dt >= 0  for all v in L2.

Method (no alias sum anywhere):
  Lift v(t) to v_n(tau), tau in [0,T).  With the Galerkin / piecewise-constant
  representation on M equal sub-intervals (v_n = vector of M sub-interval values,
  norm^2 = T/M * sum |v_i|^2), the exact chain

     v --(integral)--> x(nT) --(controller C(z), x->F)--> F[n] --(delayed hold)--> F_d

  is, at z = e^{j theta}, the M x M matrix

     G(theta) = hvec(z) * C(z)/(z-1) * s^T,     s_j = T/M
     hvec_i(z) = z^{-q} [ |I_i cap [phi T, T)| + z^{-1} |I_i cap [0, phi T)| ] / (T/M)

  (x[n] = x[n-1] + int_{(n-1)T}^{nT} v  =>  x(z) = w(z)/(z-1); the hold row is the
  exact sub-interval average of F_d).  Energy per period = (T/M) v^H G v and
  ||v||^2 = (T/M) v^H v, so the per-frequency bound is

     b*(theta) = lambda_max( -(G + G^H)/2 ),       b* = sup_theta b*(theta).

  Cross-checks: (i) the *exact* L2[0,T) lifted operator, which has range/co-range in
  span{1_[0,phiT), 1_[phiT,T)} and is therefore exactly a 2x2 (1x1 if phi=0) matrix
  in an orthonormal basis of that span; (ii) a pure time-domain finite-horizon
  computation (N periods, no z-transform): lambda_max of the symmetric part of the
  real NM x NM matrix v -> F_d, which tends to b* from below as N grows.

Usage:  /usr/bin/python3 tools/scripts/lifted_passivity.py  [--quick] [--out FILE]
Prints the tables (and writes them to FILE as Markdown). An independent check of
theory/passive_model (docs/stability-models.md): it uses no alias sum.
"""
import sys, time
import numpy as np
from scipy.optimize import minimize_scalar, minimize

T = 1e-3
QUICK = '--quick' in sys.argv


# ----------------------------------------------------------------------------
# lifted operator
# ----------------------------------------------------------------------------
def z_minus_1(theta):
    """z - 1 at z = e^{j theta}, free of cancellation for small theta."""
    return 2j * np.sin(theta / 2) * np.exp(1j * theta / 2)


def one_minus_zinv(theta):
    """1 - z^{-1} at z = e^{j theta}."""
    return 2j * np.sin(theta / 2) * np.exp(-1j * theta / 2)


def split_delay(DoT):
    q = int(np.floor(DoT + 1e-12))
    phi = DoT - q
    if abs(phi) < 1e-12:
        phi = 0.0
    return q, phi


def hold_fractions(M, phi):
    """fraction of each sub-interval lying in [0,phi T) (old sample) and [phi T,T)."""
    edges = np.arange(M + 1) / M          # in units of T
    lo, hi = edges[:-1], edges[1:]
    f_old = np.clip(np.minimum(hi, phi) - lo, 0, None) * M
    f_new = 1.0 - f_old
    return f_old, f_new


def lifted_G(theta, M, DoT, Cx):
    """theta: (n,) array; Cx: (n,) complex values of the x->F controller at z.
    Returns (n, M, M) lifted frequency response."""
    theta = np.atleast_1d(theta)
    z = np.exp(1j * theta)
    q, phi = split_delay(DoT)
    f_old, f_new = hold_fractions(M, phi)
    hvec = z[:, None] ** (-q) * (f_new[None, :] + f_old[None, :] / z[:, None])
    s = np.full(M, T / M)
    gain = Cx / z_minus_1(theta)
    return hvec[:, :, None] * gain[:, None, None] * s[None, None, :]


def bstar_lifted(theta, M, DoT, Cx, chunk=256):
    theta = np.atleast_1d(theta)
    Cx = np.broadcast_to(np.asarray(Cx, complex), theta.shape)
    out = np.empty(theta.shape)
    for k in range(0, theta.size, chunk):
        G = lifted_G(theta[k:k + chunk], M, DoT, Cx[k:k + chunk])
        H = -(G + np.conj(np.swapaxes(G, 1, 2))) / 2
        out[k:k + chunk] = np.linalg.eigvalsh(H)[:, -1]
    return out


def bstar_exact(theta, DoT, Cx):
    """exact L2[0,T) lifted operator, reduced to its 2-dim invariant span."""
    theta = np.atleast_1d(theta)
    Cx = np.broadcast_to(np.asarray(Cx, complex), theta.shape)
    z = np.exp(1j * theta)
    q, phi = split_delay(DoT)
    gain = Cx / z_minus_1(theta) * z ** (-q)
    if phi == 0.0:
        c = np.array([np.sqrt(T)])
        a = np.stack([gain * np.sqrt(T)], -1)
    else:
        c = np.array([np.sqrt(phi * T), np.sqrt((1 - phi) * T)])
        a = np.stack([gain / z * np.sqrt(phi * T), gain * np.sqrt((1 - phi) * T)], -1)
    G = a[:, :, None] * c[None, None, :]          # G = a c^T (operator v -> a <1,v>)
    H = -(G + np.conj(np.swapaxes(G, 1, 2))) / 2
    lam = np.linalg.eigvalsh(H)[:, -1]
    return np.maximum(lam, 0.0)                   # orthogonal complement is kernel (eig 0)


# ----------------------------------------------------------------------------
# controllers: transfer x -> F at z
# ----------------------------------------------------------------------------
def Cx_wall(theta, K, B):
    return K + B * one_minus_zinv(np.atleast_1d(theta)) / T


def Zc_coupling(theta, kc, bc):
    return bc + kc * T / one_minus_zinv(np.atleast_1d(theta))   # z/(z-1) = 1/(1-z^-1)


def Cx_from_Z(theta, Z):
    return Z * one_minus_zinv(np.atleast_1d(theta)) / T                   # F = Z v*,  v* = (1-z^-1) x / T


# ----------------------------------------------------------------------------
# time-domain finite-horizon check (virtual wall), no z-transform
# ----------------------------------------------------------------------------
def bstar_timedomain(N, Mt, DoT, K, B):
    q, phi = split_delay(DoT)
    f_old, f_new = hold_fractions(Mt, phi)
    n = N * Mt
    # w[k] = int over period k of v = T/Mt * sum_j v[k,j]
    W = np.kron(np.eye(N), np.full((1, Mt), T / Mt))          # N x n
    X = np.tril(np.ones((N, N)), -1) @ W                      # x[n] = sum_{k<n} w[k]
    Xm1 = np.vstack([np.zeros((1, n)), X[:-1]])               # x[n-1]
    F = K * X + B * (X - Xm1) / T                             # N x n
    def shift(A, s):                                          # row k <- row k-s
        out = np.zeros_like(A)
        if s < N:
            out[s:] = A[:N - s]
        return out
    Fnew, Fold = shift(F, q), shift(F, q + 1)
    L = (np.kron(Fnew, np.ones((Mt, 1))) * np.tile(f_new, N)[:, None]
         + np.kron(Fold, np.ones((Mt, 1))) * np.tile(f_old, N)[:, None])
    Hs = -(L + L.T) / 2
    return np.linalg.eigvalsh(Hs)[-1]


# ----------------------------------------------------------------------------
# sup over theta: fine grid + local refinement
# ----------------------------------------------------------------------------
THETA_GRID = np.unique(np.concatenate([np.logspace(-6, 0, 601),
                                       np.linspace(1e-3, np.pi, 3001 if not QUICK else 601),
                                       [np.pi]]))


def sup_theta(fun):
    """fun(theta array)->values. Returns (sup, theta_star, note)."""
    vals = fun(THETA_GRID)
    i = int(np.argmax(vals))
    if np.ptp(vals) < 1e-8 * max(1.0, abs(vals.max())):
        return vals.max(), None, 'flat (all theta)'
    if i == len(THETA_GRID) - 1:
        return vals[i], np.pi, 'pi'
    if i == 0:
        return vals[i], THETA_GRID[0], '0+'
    lo, hi = THETA_GRID[i - 1], THETA_GRID[i + 1]
    r = minimize_scalar(lambda t: -fun(np.array([t]))[0], bounds=(lo, hi),
                        method='bounded', options={'xatol': 1e-12})
    if -r.fun >= vals[i]:
        return -r.fun, r.x, 'interior'
    return vals[i], THETA_GRID[i], 'interior(grid)'


# ----------------------------------------------------------------------------
# case (c): worst case over passive environments at fixed theta
# ----------------------------------------------------------------------------
def W_line(theta, DoT, kc, bc, M=8):
    """max of b*(theta) over lossless Ye = j h (the boundary of the admissible
    Z-disk; b*(theta) is convex in Z so the max over the disk lies there)."""
    yc = 1 / Zc_coupling(theta, kc, bc)[0]
    sc = abs(yc)
    u = np.concatenate([-np.logspace(4, -4, 400), [0], np.logspace(-4, 4, 400)]) * sc
    Zs = 1 / (yc + 1j * u)
    vals = bstar_lifted(np.full(u.shape, theta), M, DoT, Cx_from_Z(theta, Zs))
    i = int(np.argmax(vals))
    lo, hi = u[max(i - 1, 0)], u[min(i + 1, len(u) - 1)]
    f = lambda hh: -bstar_lifted(np.array([theta]), M, DoT,
                                 Cx_from_Z(theta, 1 / (yc + 1j * hh)))[0]
    r = minimize_scalar(f, bounds=(lo, hi), method='bounded', options={'xatol': 1e-13 * sc})
    return (max(vals[i], -r.fun), (0.0, r.x if -r.fun >= vals[i] else u[i]))


def W_case_c(theta, DoT, kc, bc, M=8, nstart=None, rng=None):
    rng = np.random.default_rng(0) if rng is None else rng
    zc = Zc_coupling(theta, kc, bc)[0]
    yc = 1 / zc

    def bval(g, h):
        Z = 1 / (yc + g + 1j * h)
        return bstar_lifted(np.array([theta]), M, DoT, Cx_from_Z(theta, Z))[0]

    # scale of admittances: |1/Zc|
    sc = abs(yc)
    best = (-np.inf, None)
    # (1) many-start 2-D Nelder-Mead on (g = s^2 * sc, h = u * sc)
    starts = []
    for gs in [0.0, 0.03, 0.3, 1.0, 3.0]:
        for hs in [-100, -10, -3, -1, -0.3, -0.1, 0, 0.1, 0.3, 1, 3, 10, 100]:
            starts.append((np.sqrt(gs), hs))
    for _ in range(10 if nstart is None else nstart):
        starts.append((abs(rng.normal()) * 2, rng.normal() * 10))
    for s0, u0 in starts:
        f = lambda p: -bval((p[0] ** 2) * sc, p[1] * sc)
        r = minimize(f, [s0, u0], method='Nelder-Mead',
                     options={'xatol': 1e-10, 'fatol': 1e-14, 'maxiter': 4000})
        if -r.fun > best[0]:
            best = (-r.fun, ((r.x[0] ** 2) * sc, r.x[1] * sc))
    # (2) lossless boundary g = 0: dense 1-D scan in h (incl. |h| -> inf) + refine
    g0 = W_line(theta, DoT, kc, bc, M)
    # (3) independent check: Z = 1/(yc+Ye) sweeps the disk |Z - 1/(2r)| <= 1/(2r),
    #     r = Re(yc); scan its boundary circle
    rr = yc.real
    psi = np.linspace(0, 2 * np.pi, 20001)
    Zb = (1 + np.exp(1j * psi)) / (2 * rr)
    vb = bstar_lifted(np.full(psi.shape, theta), M, DoT, Cx_from_Z(theta, Zb)).max()
    W = max(best[0], g0[0])
    arg = best[1] if best[0] >= g0[0] else g0[1]
    Zopt = 1 / (yc + arg[0] + 1j * arg[1])
    W512 = bstar_lifted(np.array([theta]), 512, DoT, Cx_from_Z(theta, Zopt))[0]
    return W, arg, best[0], g0[0], vb, 2 * yc.real, W512


# ----------------------------------------------------------------------------
def fmt(x, n=7):
    return f'{x:.{n}g}'


def main():
    t0 = time.time()
    out = []
    P = lambda s='': (print(s), out.append(s))
    DLIST = [0, 0.25, 0.5, 0.75, 1, 1.5, 2]
    Mref = 64

    P('# Lifted-operator reference for sampled-data passivity bound b*')
    P('')
    P(f'T = {T} s. Command: `/usr/bin/python3 tools/scripts/lifted_passivity.py`')
    P('')

    # ---------------- validation: Colgate & Schenkel, D=0
    P('## 0. Validation vs Colgate & Schenkel (D = 0): b* = K T/2 + B')
    P('')
    P('| K | B | b* lifted (M=64) | K T/2 + B | rel.err |')
    P('|---|---|---|---|---|')
    for K, B in [(1000, 0), (1000, 0.3), (1000, 1.0), (5000, 0.1), (200, 2.0)]:
        v, th, note = sup_theta(lambda t: bstar_lifted(t, Mref, 0, Cx_wall(t, K, B)))
        ref = K * T / 2 + B
        P(f'| {K} | {B} | {fmt(v, 10)} | {fmt(ref, 10)} | {abs(v - ref) / ref:.1e} |')
    P('')

    # ---------------- convergence in M
    P('## Convergence in M (controller (a), K=1000, B=0.3), b*(theta) at theta = 0.7 and 3.0')
    P('')
    P('| D/T | M | b*(0.7) | b*(3.0) | |diff vs exact 2x2| max |')
    P('|---|---|---|---|---|')
    K, B = 1000, 0.3
    th2 = np.array([0.7, 3.0])
    for DoT in [0.25, 0.5, 1.5]:
        ex = bstar_exact(th2, DoT, Cx_wall(th2, K, B))
        for M in [64, 128, 256, 512, 63, 127, 255, 511]:
            v = bstar_lifted(th2, M, DoT, Cx_wall(th2, K, B))
            P(f'| {DoT} | {M} | {fmt(v[0], 10)} | {fmt(v[1], 10)} | {np.abs(v - ex).max():.2e} |')
        P(f'| {DoT} | exact | {fmt(ex[0], 10)} | {fmt(ex[1], 10)} | 0 |')
    P('')

    # ---------------- tables 1 & 2
    for tab, B in [(1, 0.0), (2, 0.3)]:
        K = 1000
        P(f'## {tab}. Controller (a), K = {K} N/m, B = {B} N s/m')
        P('')
        P('| D/T | b* (M=64) | b* (M=512) | b* exact-2x2 | theta* | b*/(K T/2) | time-domain N=400 (M=4) |')
        P('|---|---|---|---|---|---|---|')
        for DoT in DLIST:
            v64, th, note = sup_theta(lambda t: bstar_lifted(t, 64, DoT, Cx_wall(t, K, B)))
            ex, the, notee = sup_theta(lambda t: bstar_exact(t, DoT, Cx_wall(t, K, B)))
            thq = np.array([th if th is not None else 1.0])
            v512 = bstar_lifted(thq, 512, DoT, Cx_wall(thq, K, B))[0]
            td = bstar_timedomain(400 if not QUICK else 150, 4, DoT, K, B)
            ths = {'flat (all theta)': 'flat (all theta)', '0+': '0+ (sup as theta->0+; value at 1e-6)',
                   'pi': 'pi'}.get(note, f'{th:.9g}' if th is not None else note)
            P(f'| {DoT} | {fmt(v64, 10)} | {fmt(v512, 10)} | {fmt(ex, 10)} | {ths} | '
              f'{fmt(v64 / (K * T / 2), 8)} | {fmt(td, 8)} |')
        P('')

    # ---------------- table 3
    P('## 3. b*(theta), controller (a), K = 1000, B = 0 (M = 64; M = 512 identical to <1e-12)')
    P('')
    TH3 = np.array([1e-3, 0.01, 0.1, 0.5, 1, 2, 3, np.pi])
    P('| theta | ' + ' | '.join(f'D/T={d}' for d in [0, 0.5, 1]) + ' |')
    P('|---|---|---|---|')
    cols = []
    for DoT in [0, 0.5, 1]:
        a = bstar_lifted(TH3, 64, DoT, Cx_wall(TH3, 1000, 0))
        b = bstar_lifted(TH3, 512, DoT, Cx_wall(TH3, 1000, 0))
        c = bstar_exact(TH3, DoT, Cx_wall(TH3, 1000, 0))
        assert np.abs(a - b).max() < 1e-9 and np.abs(a - c).max() < 1e-9, (a, b, c)
        cols.append(a)
    for k, th in enumerate(TH3):
        lab = 'pi' if th == np.pi else f'{th:g}'
        P(f'| {lab} | ' + ' | '.join(f'{cols[j][k]:.6g}' for j in range(3)) + ' |')
    P('')

    # ---------------- table 4
    TH4 = np.array([0.01, 0.1, 0.5, 1, 2, 3, np.pi])
    for kc, bc in [(1000, 0.2), (3000, 0.05)]:
        P(f'## 4. Case (c): kc = {kc} N/m, bc = {bc} N s/m, worst case over Re Ye >= 0')
        P('')
        P('W(theta) = max over Ye of b*(theta) [2-D Nelder-Mead, 75 starts; g=0 scan; disk-boundary scan], '
          'P(theta) = W(theta) * 2 Re(1/Zc(e^{j theta})).')
        P('')
        P('Optimisation with lifted M=8 (grid-aligned, exact); last-but-one column re-evaluates the optimum with M=512.')
        P('')
        P('| D/T | theta | W (2-D opt) | W (g=0 line) | W (disk boundary) | argmax Ye = g + j h [m/(N s)] | W at argmax, M=512 | P = W*2Re(1/Zc) |')
        P('|---|---|---|---|---|---|---|---|')
        for DoT in [0, 0.5, 1]:
            for th in TH4:
                W, (g, h), w2d, wg0, wdisk, twor, W512 = W_case_c(th, DoT, kc, bc)
                lab = 'pi' if th == np.pi else f'{th:g}'
                P(f'| {DoT} | {lab} | {fmt(w2d, 9)} | {fmt(wg0, 9)} | {fmt(wdisk, 9)} | '
                  f'{g:.3g} {"+" if h >= 0 else "-"} j{abs(h):.6g} | {fmt(W512, 9)} | {fmt(W * twor, 9)} |')
            # sup over theta of W: use the disk-boundary characterisation on a grid + refine
            def Wfun(tt):
                return np.array([W_line(t, DoT, kc, bc)[0] for t in np.atleast_1d(tt)])
            tg = np.unique(np.concatenate([np.logspace(-5, 0, 51), np.linspace(0.02, np.pi, 157)]))
            vals = Wfun(tg)
            i = int(np.argmax(vals))
            if i == len(tg) - 1:
                Wmax, thmax = vals[i], np.pi
            elif i == 0:
                Wmax, thmax = vals[i], tg[0]
            else:
                r = minimize_scalar(lambda t: -Wfun(t)[0], bounds=(tg[max(i - 1, 0)], tg[i + 1]),
                                    method='bounded', options={'xatol': 1e-9})
                Wmax, thmax = max(-r.fun, vals[i]), r.x
            # confirm at the maximiser with the full 2-D optimiser
            Wc, _, _, _, _, _, Wc512 = W_case_c(thmax, DoT, kc, bc)
            where = f'theta = {thmax:.7g}' + (' (sup as theta->0+)' if i == 0 else '')
            P(f'| {DoT} | **max over theta** at {where} | {fmt(Wc, 9)} | {fmt(Wmax, 9)} | | | {fmt(Wc512, 9)} | '
              f'{fmt(Wc * 2 * (1 / Zc_coupling(thmax, kc, bc)[0]).real, 9)} |')
        P('')
    # time-domain convergence in N
    P('## Time-domain finite-horizon check: convergence in N (controller (a), K=1000, B=0.3, Mt=4)')
    P('')
    P('| D/T | N=100 | N=200 | N=400 | N=800 | lifted sup |')
    P('|---|---|---|---|---|---|')
    for DoT in [0.5, 1.5]:
        tds = [bstar_timedomain(N, 4, DoT, 1000, 0.3) for N in (100, 200, 400, 800)]
        ls = sup_theta(lambda t: bstar_lifted(t, 64, DoT, Cx_wall(t, 1000, 0.3)))[0]
        P(f'| {DoT} | ' + ' | '.join(fmt(x, 9) for x in tds) + f' | {fmt(ls, 9)} |')
    P('')
    P(f'(wall time {time.time() - t0:.0f} s)')
    if '--out' in sys.argv:
        with open(sys.argv[sys.argv.index('--out') + 1], 'w') as f:
            f.write('\n'.join(out) + '\n')


if __name__ == '__main__':
    main()
