"""What a stiffly stable step would save in BP1-QD (docs/studies/cycles.md, "Against the
target"): over the first cycle at dz = 200 m (to a year after the first event), the
builder's explicit pair (Bogacki-Shampine 3(2) at 1e-4) against Radau IIA of order 5
(scipy's, at 1e-4 and 1e-5), each event start against Dormand-Prince 5(4) at 1e-7; and
how close the explicit pair's steps come to its stability limit, from the eigenvalues of
the Jacobian at sampled steps.

    python -m studies.cycles.stiff [-o OUT] [--dz 200]

writes OUT/stiff.json. The Jacobian of the rates y' = f(y) (y: slip, then the state psi) is

    J = [[D_v K, P_v], [D_psi K, P_psi]]

K = d tau / d slip (the static response, affine in the slip: one column per unit slip, built
once), D = d f / d tau at each point and P = d f / d psi (the point's own psi, or its mirror
image's, which the solve takes): central differences of f under a uniform shift of the load
and of psi, four evaluations of f a Jacobian."""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

EVENT = 1e-3        # m/s: an event while the largest slip rate exceeds it
SAMPLES = 12        # states in events and between them whose eigenvalues are computed


def _reach(pair):
    """(theta, r(theta)): how far ``pair``'s stability region (|R(z)| <= 1, run.stability_polynomial)
    reaches along each ray z = r e^(i theta), theta in [pi/2, pi] (the first exit, to 2e-4)."""
    from studies.cycles.run import stability_polynomial

    coef = stability_polynomial(pair)[::-1]
    theta = np.linspace(np.pi / 2, np.pi, 1001)
    r = np.linspace(1e-4, 4.0, 20001)
    out = np.abs(np.polyval(coef, r[None, :] * np.exp(1j * theta[:, None]))) > 1 + 1e-12
    return theta, r[np.maximum(np.where(out.any(1), out.argmax(1), r.size - 1) - 1, 0)]


class Problem:
    """BP1-QD at ``dz`` to ``years``: the system, its rates counted, its Jacobian."""

    def __init__(self, dz, years, tolerance=None):
        from cracklab.scenes import bp1
        from cracklab.solver.sequence.run import system_of

        self.scene = bp1(dz=dz, years=years, tolerance=tolerance)
        self.year = self.scene.t_end / years
        s = self.system = system_of(self.scene)
        self.probe = system_of(self.scene)          # the largest slip rate at a step's end, not counted
        n = self.n = s.n
        self.c = s.comps[0]
        self.L, self.a, _ = s.error_weights()
        self.rep = np.minimum(np.arange(n), s.image) if s.image is not None else np.arange(n)
        y = np.zeros(2 * n)
        base = s.traction(0.0, y)[self.c].copy()
        self.K = np.empty((n, n))
        for j in range(n):
            y[j] = 1.0
            self.K[:, j] = s.traction(0.0, y)[self.c] - base
            y[j] = 0.0
        self.evaluations = 0
        self._rates, self._stage_rates = s.rates, s.stage_rates

    def rates(self, t, y):
        self.evaluations += 1
        return self._rates(t, y)

    def stage_rates(self, t, y, h, w, k, i):
        self.evaluations += 1
        return self._stage_rates(t, y, h, w, k, i)

    def jacobian(self, t, y):
        s, n, c = self.system, self.n, self.c
        self.rates(t, y)
        eps = 1e-5 * (s.sigma * self.a + s.eta * s.last[0])
        tau0 = s.tau0[c]
        try:
            s.tau0[c] = tau0 + eps
            fp = self.rates(t, y)
            s.tau0[c] = tau0 - eps
            fm = self.rates(t, y)
        finally:
            s.tau0[c] = tau0
        d_tau = (fp - fm) / np.concatenate([2 * eps, 2 * eps])
        dpsi = 1e-5 * self.a
        yp, ym = y.copy(), y.copy()
        yp[n:] += dpsi
        ym[n:] -= dpsi
        d_psi = (self.rates(t, yp) - self.rates(t, ym)) / np.concatenate([2 * dpsi[self.rep]] * 2)
        J = np.zeros((2 * n, 2 * n))
        J[:n, :n] = d_tau[:n, None] * self.K
        J[n:, :n] = d_tau[n:, None] * self.K
        i = np.arange(n)
        J[i, n + self.rep] = d_psi[:n]
        J[n + i, n + self.rep] = d_psi[n:]
        return J

    def vmax(self, t, y):
        self.probe.rates(t, y)
        return float(self.probe.last[0].max())


def explicit(dz, years, tolerance=None, after_event=None, keep=False):
    """The builder's pair (or the one of ``tolerance``) to ``years``, or to ``after_event``
    seconds after the first event ends: counts, the event's start (log-linear in the largest
    slip rate between the steps around it), the states when ``keep``."""
    from cracklab.solver.sequence.control import StepControl
    from cracklab.solver.sequence.integrate import integrate
    from cracklab.solver.sequence.pairs import PAIRS
    from cracklab.solver.sequence.run import steps_of

    p = Problem(dz, years, tolerance)
    s, seq = p.system, p.scene.sequence
    dt_min, dt_max, dt_first = steps_of(p.scene)
    control = StepControl(tolerance=seq.tolerance, dt_min=dt_min, dt_max=dt_max, dt_first=dt_first)
    s.rates, s.stage_rates = p.rates, p.stage_rates
    y0 = s.initial()
    prev = (0.0, p.vmax(0.0, y0))
    start = end = None
    rows = []
    t0 = time.perf_counter()
    for acc in integrate(s, y0, 0.0, p.scene.t_end, PAIRS[seq.pair], control, dt=dt_first):
        v = float(s.last[0].max())
        rows.append((acc.t, acc.dt, v, acc.rejected, acc.y.copy() if keep else None))
        if start is None and v > EVENT:
            r = (np.log(EVENT) - np.log(prev[1])) / (np.log(v) - np.log(prev[1]))
            start = prev[0] + r * (acc.t - prev[0])
        if start is not None and end is None and v <= EVENT:
            end = acc.t
        prev = (acc.t, v)
        if after_event is not None and end is not None and acc.t > end + after_event:
            break
    wall = time.perf_counter() - t0
    v = np.array([r[2] for r in rows])
    return p, rows, {"method": seq.pair, "tolerance": seq.tolerance, "steps": len(rows),
                     "steps_in_event": int(np.sum(v > EVENT)), "rejected": int(sum(r[3] for r in rows)),
                     "evaluations": p.evaluations, "wall_s": wall, "t_end_s": rows[-1][0],
                     "event_start_s": start}


def radau(dz, years, t_end, tolerance):
    """Radau IIA (scipy) over [0, t_end] with the Jacobian above: counts and the event's start
    (bisection on the method's own dense output)."""
    from scipy.integrate import Radau

    p = Problem(dz, years)
    y0 = p.system.initial()
    scale = np.concatenate([p.L, p.a])
    solver = Radau(p.rates, 0.0, y0, t_end, rtol=tolerance, atol=tolerance * scale, jac=p.jacobian,
                   max_step=p.year)
    steps = inside = 0
    prev, start = 0.0, None
    t0 = time.perf_counter()
    while solver.status == "running":
        solver.step()
        if solver.status == "failed":
            raise RuntimeError(f"Radau failed at t = {solver.t:g} s")
        steps += 1
        v = p.vmax(solver.t, solver.y)
        inside += v > EVENT
        if start is None and v > EVENT:
            dense, lo, hi = solver.dense_output(), prev, solver.t
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if p.vmax(mid, dense(mid)) > EVENT else (mid, hi)
            start = 0.5 * (lo + hi)
        prev = solver.t
    return {"method": "radau", "tolerance": tolerance, "steps": steps, "steps_in_event": int(inside),
            "evaluations": p.evaluations, "jacobians": solver.njev, "factorisations": solver.nlu,
            "wall_s": time.perf_counter() - t0, "event_start_s": start}


def stability(p, rows):
    """Medians over sampled steps in events and between them of (the step taken from a state)
    / (the largest step the scene's pair is stable for at the Jacobian's eigenvalues)."""
    from cracklab.solver.sequence.pairs import PAIRS

    theta, reach = _reach(PAIRS[p.scene.sequence.pair])
    v = np.array([r[2] for r in rows])
    out = {}
    for name, idx in (("event", np.flatnonzero(v > EVENT)), ("between", np.flatnonzero(v <= EVENT))):
        idx = idx[idx + 1 < len(rows)]
        pick = np.unique(idx[np.linspace(0, idx.size - 1, SAMPLES).astype(int)])
        ratios = []
        for i in pick:
            lam = np.linalg.eigvals(p.jacobian(rows[i][0], rows[i][4]))
            lam = lam[lam.real < 0]
            limit = np.min(np.interp(np.pi - np.abs(np.angle(-lam)), theta, reach) / np.abs(lam))
            ratios.append(rows[i + 1][1] / limit)
        out[name] = {"samples": int(pick.size), "median": float(np.median(ratios)), "largest": float(np.max(ratios))}
    return out


def study(dz=200.0, log=print) -> dict:
    """Every figure of OUT/stiff.json at ``dz``."""
    p, rows, bs3 = explicit(dz, 400.0, after_event=3.15576e7, keep=True)
    years, t_end = 400.0, bs3["t_end_s"]
    log(f"Bogacki-Shampine 3(2): {bs3['steps']} steps to {t_end / p.year:.3f} years", flush=True)
    _, _, ref = explicit(dz, years, tolerance=1e-7, after_event=0.0)
    res = {"dz": dz, "t_end_yr": t_end / p.year, "window_points": p.n, "reference": ref,
           "stability": stability(p, rows), "runs": [bs3]}
    for tol in (1e-4, 1e-5):
        res["runs"].append(radau(dz, years, t_end, tol))
        log(f"Radau at {tol:g}: {res['runs'][-1]['steps']} steps", flush=True)
    for r in res["runs"]:
        r["event_start_error_yr"] = (r["event_start_s"] - ref["event_start_s"]) / p.year
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default="out/cycles")
    ap.add_argument("--dz", type=float, default=200.0)
    args = ap.parse_args(argv)
    res = study(args.dz)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "stiff.json").write_text(json.dumps(res, indent=1))
    print(json.dumps({k: v for k, v in res.items() if k != "runs"} | {"runs": res["runs"]}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
