"""Slip and state of a rate-and-state plane as one ODE system, quasi-dynamic (docs/reference/
equations.md, "Sequences: the quasi-dynamic response"): at time t, with slip delta and state
psi,

    tau*_j = tau0_j + F_j[delta] + k (V_p,j t - <delta_j>)        (the static response, static.py)
    |tau*| - eta V = sigma f(V, psi),   v_j = V tau*_j / |tau*|     (step (v), no state update)
    d delta_j / dt = v_j,   d psi / dt = G(V, psi)                  (the law's evolution)

where the plane slides; on the creeping region v_j = V_p,j (kinematic), on bonded points
v_j = 0. eta = mu / (2 c_s), the radiation damping of Eq. (4). The unknowns are one flat
array y = (delta_j for each slipping component, psi)."""
from __future__ import annotations

import numpy as np

from ...errors import InputError
from ...jit import njit
from .integrate import weighted
from .mirror import mirror_index
from .static import StaticResponse
from .window import WindowedStatic, into_box, out_of_box


class QuasiDynamic:
    """The system of ``material``, ``grid``, the ``law`` (one that heals), ``tau0``
    ({component: field or number}, the shear load), ``sigma`` (compressive normal stress,
    field or number), ``plate`` ({component: V_p >= 0} of every slipping shear component),
    ``creep`` (mask of the creeping region, or None), ``stiffness`` (the spring on the mean
    slip, stress per length): the values of a Scene, which checked them (model/sequence.py,
    ``Sequence.check_scene``; ``system_of`` in run.py builds the system of a scene)."""

    def __init__(self, material, grid, law, tau0, sigma, plate, creep=None, stiffness=0.0, transforms=None,
                 mirror=False, window=False):
        comps = tuple(sorted(plate))
        shape = grid.shape
        self.grid, self.law, self.comps = grid, law, comps
        self.plate = {c: float(v) for c, v in plate.items()}
        bonded = np.zeros(shape, bool) if law.bonded is None else np.broadcast_to(np.asarray(law.bonded, bool), shape)
        creep = np.zeros(shape, bool) if creep is None else np.broadcast_to(np.asarray(creep, bool), shape)
        self.stiffness = float(stiffness)
        self.static = StaticResponse(material, grid, comps, stiffness=self.stiffness, transforms=transforms)
        self.eta = material.eta(comps[0])
        tau0 = {c: np.broadcast_to(np.asarray(tau0.get(c, 0.0), dtype=float), shape).ravel() for c in comps}
        sigma = np.broadcast_to(np.asarray(sigma, dtype=float), shape).ravel()
        slides = (~bonded & ~creep).ravel()
        if np.any(sigma[slides] <= 0) or not np.all(np.isfinite(sigma)):
            raise InputError("law.sigma_n", "must be finite and > 0 (compressive) where the plane slides")
        # the unknowns' nodes (``points``): the whole grid, or (``window``) the window of the
        # nodes that do not creep, when its transforms are smaller than the grid's (window.py)
        self.window = None
        if window and np.any(creep) and not grid.free_surface:
            win = WindowedStatic(self.static, grid, ~creep)
            self.window = win if win.worth else None
        self.points = np.arange(int(np.prod(shape))) if self.window is None else self.window.points
        pts = self.points
        self.n = pts.size
        self.creep = np.ascontiguousarray(creep.ravel()[pts])
        self.slides = np.ascontiguousarray(slides[pts])
        # the law's parameters are fields over the grid: its points are given as a mask of it
        at = np.zeros(slides.size, bool)
        at[pts[self.slides]] = True
        self.at = self.at_slides = slides if self.window is None else at
        self.tau0 = {c: np.ascontiguousarray(x[pts]) for c, x in tau0.items()}
        self._tau0_grid = tau0 if self.window is not None else None     # for the fields over the grid
        self.sigma = np.ascontiguousarray(sigma[pts])
        self.sigma_s = np.ascontiguousarray(self.sigma[self.slides])
        self.plate_speed = float(np.sqrt(sum(v * v for v in self.plate.values())))
        # the error's scales (``error_weights``): L and a at every point
        self._L, self._a = (np.broadcast_to(np.asarray(getattr(law, name), dtype=float), shape).ravel()[pts]
                            for name in ("L", "a"))
        # the state at t = 0 (``initial``), from the load over the grid
        T = np.sqrt(sum(x ** 2 for x in tau0.values()))
        with np.errstate(divide="ignore", invalid="ignore"):
            psi = law.initial_state(T.reshape(shape), sigma.reshape(shape), self.eta).ravel().astype(float)
        self._psi0 = np.where(slides, psi, 0.0)[pts]     # a Scene's load slides at V_ini where it slides
        # Sequence.mirror: each node's image about x1 = 0, whose traction is made the same
        self.image = None
        if mirror:
            self._image_grid = mirror_index(shape)
            image = self._image_grid[pts]
            self.image = np.searchsorted(pts, image)
            if not np.array_equal(pts[np.minimum(self.image, pts.size - 1)], image):   # pragma: no cover
                raise InputError("sequence.creep", "must be even about x1 = 0 with sequence.mirror")
        # with the mirror the solve runs at one of each sliding node and its image (``_half``:
        # their places among the sliding nodes; ``_both``: the place in _half of each one's)
        self._half = self._both = None
        slid = np.flatnonzero(self.slides)
        if self.image is not None and slid.size:
            mate = np.searchsorted(slid, self.image[slid])
            if np.array_equal(slid[np.minimum(mate, slid.size - 1)], self.image[slid]):
                k = np.arange(slid.size)
                self._half = np.flatnonzero(k <= mate)
                self._both = np.searchsorted(self._half, np.minimum(k, mate))
                self.at = np.zeros(slides.size, bool)
                self.at[pts[slid[self._half]]] = True
                self._sigma_half = np.ascontiguousarray(self.sigma_s[self._half])
        self.solved = int(np.count_nonzero(self.slides)) if self._half is None else self._half.size
        # one slipping component: ``rates`` gathers and scatters in two compiled passes
        # (``_gather``, ``_scatter``), the same arithmetic as the general path's
        self._slid = slid.astype(np.int64)
        self._creep_at = np.flatnonzero(self.creep).astype(np.int64)
        every = np.arange(slid.size, dtype=np.int64)
        self._solve_at = every if self._half is None else self._half.astype(np.int64)
        self._solve_of = every if self._half is None else self._both.astype(np.int64)
        self._image_at = np.zeros(0, np.int64) if self.image is None else self.image.astype(np.int64)
        self._sigma_solved = self.sigma_s if self._half is None else self._sigma_half
        self._kept_places = self._kept_region = None
        # one component on a window with FFTW (the static response: a system of dynamic.py has
        # no window): a stage's sums, the window's box, the traction and the rates go through
        # compiled passes and the window's plans (``stage_rates``)
        self._fused = self.window is not None and self.window.fftw and len(comps) == 1
        self.lnV = None     # the last solve's ln V (at the ``solved`` points): Newton's guesses for the next
        self.last = None    # (V, tau, v) of the last evaluation of ``rates``

    # -- the unknowns
    def split(self, y):
        """({component: slip}, psi) views of the flat array ``y``."""
        n = self.n
        return {c: y[i * n:(i + 1) * n] for i, c in enumerate(self.comps)}, y[len(self.comps) * n:]

    def initial(self):
        """y at t = 0: no slip, and the law's initial state under the load at t = 0."""
        return np.concatenate([np.zeros(self.n * len(self.comps)), self._psi0])

    def on_points(self, x):
        """``x`` at the unknowns' points: the unknowns or their rates (one block per component
        and psi), or a field, as this system holds them or over the whole grid (a checkpoint
        written by a run that held the whole grid)."""
        x = np.asarray(x, dtype=float)
        N, blocks = int(np.prod(self.grid.shape)), len(self.comps) + 1
        if x.size in (self.n, blocks * self.n) or self.window is None:
            return x
        return x[self.points] if x.size == N else x.reshape(blocks, N)[:, self.points].ravel()

    def traction(self, t, y):
        """{component: tau*} at (t, y): load, elastic response and the spring's load."""
        delta, _ = self.split(y)
        F = self.elastic(delta, t)
        tau = {c: self.tau0[c] + F[c] + self.stiffness * self.plate[c] * t for c in self.comps}
        if self.image is not None:      # exactly even: the same solve at a node and its image
            tau = {c: 0.5 * (x + x[self.image]) for c, x in tau.items()}
        return tau

    def elastic(self, delta: dict, t=0.0) -> dict:
        """{component: F} of the slips ``delta`` at the unknowns' points (flat) at time ``t``:
        the static response (on the window: of the slip less V_p t, less k V_p t, window.py)."""
        if self.window is not None:
            F = self.window.traction(delta, {c: self.plate[c] * t for c in self.comps})
            if self.stiffness:
                F = {c: x - self.stiffness * self.plate[c] * t for c, x in F.items()}
            return F
        shape = self.grid.shape
        F = self.static.traction({c: delta[c].reshape(shape) for c in self.comps})
        return {c: x.ravel() for c, x in F.items()}

    def fields(self, t, y, last) -> "Fields":
        """The fields at (t, y), ``last`` the evaluation there: :class:`Fields`."""
        return Fields(self, t, y, last)

    def _region(self, s1, s3):
        """(the places among the window's points of the grid's nodes [s1, s3], the first of
        those nodes outside the window or -1), kept for the last slices asked."""
        key = (s1, s3)
        kept = self._kept_region
        if kept is not None and kept[0] == key:
            return kept[1], kept[2]
        shape = self.grid.shape
        nodes = np.arange(int(np.prod(shape))).reshape(shape)[s1, s3].ravel()
        at, on = _locate(self.points, nodes)
        out = nodes[~on]
        self._kept_region = (key, np.ascontiguousarray(at[on]), int(out[0]) if out.size else -1)
        return self._kept_region[1], self._kept_region[2]

    def _places(self, nodes):
        """(the place among the window's points of each of the flat grid indices ``nodes``,
        whether it is one of them, whether all are), kept for the last array asked (a
        recorder's stations)."""
        kept = self._kept_places
        if kept is not None and kept[0] is nodes:
            return kept[1:]
        at, on = _locate(self.points, nodes)
        self._kept_places = (nodes, at, on, bool(np.all(on)))
        return self._kept_places[1:]

    def stage(self, dt, rates, c) -> None:
        """Before the stage i ``dt`` = c_i h into a step, with the rates of the stages before it
        (``rates``, a row each) and ``c`` = (c_0 .. c_i): nothing for the static response
        (dynamic.py prepares its history here)."""

    def stage_rates(self, t, y, h, w, k, i):
        """The unknowns of a stage, y + h sum_l w_l k_l (the rows of ``k``, the first
        ``w.size`` of them), and their rates at time ``t`` into ``k[i]``: ``rates`` of them
        (one component on a window: its arithmetic in fewer passes, the same numbers)."""
        yi = weighted(y, h, w, k)
        if self._fused:
            self._evaluate_one(t, yi, k[i])
        else:
            k[i] = self.rates(t, yi)
        return yi

    def rates(self, t, y):
        """dy/dt at (t, y); keeps (V, tau, v) of the evaluation in ``last``."""
        if len(self.comps) == 1:
            return self._rates_one(t, y)
        delta, psi = self.split(y)
        tau = self.traction(t, y)
        s = self.slides
        if len(self.comps) == 1:
            ts = {self.comps[0]: tau[self.comps[0]][s]}
            T = np.abs(ts[self.comps[0]])
        else:
            ts = {c: tau[c][s] for c in self.comps}
            T = np.sqrt(sum(x * x for x in ts.values()))
        if self._half is None:
            Vs, self.lnV, dps = self.law.slide_rates(T, psi[s], self.sigma_s, self.eta, guess=self.lnV, at=self.at)
        else:       # a node and its image: the same traction, the same state
            h = self._half
            Vh, self.lnV, dph = self.law.slide_rates(T[h], psi[s][h], self._sigma_half, self.eta, guess=self.lnV,
                                                     at=self.at)
            Vs, dps = Vh[self._both], dph[self._both]
        dy = np.zeros_like(y)
        dd, dpsi = self.split(dy)
        V = np.zeros(self.n)
        V[s] = Vs
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(T > 0, Vs / T, 0.0)
        for c in self.comps:
            dd[c][s] = ratio * ts[c]
            dd[c][self.creep] = self.plate[c]
            tau[c] -= self.eta * dd[c]
        V[self.creep] = self.plate_speed
        dpsi[s] = dps
        self.last = (V, tau, {c: dd[c].copy() for c in self.comps})
        return dy

    def _rates_one(self, t, y):
        """``rates`` of one slipping component: the traction gathered at the points solved
        (a node and its image once) and the solve's rates scattered back, compiled."""
        n, c = self.n, self.comps[0]
        if self._fused:
            return self._evaluate_one(t, y, np.empty_like(y))
        F = self.elastic({c: y[:n]}, t)[c]
        tau = np.empty(n)
        T = np.empty(self._solve_at.size)
        psi = np.empty(self._solve_at.size)
        _gather(self.tau0[c], F, self.stiffness * self.plate[c] * t, self._image_at, self._slid, self._solve_at,
                y[n:], tau, T, psi)
        return self._solve_one(tau, T, psi, np.zeros_like(y))

    def _evaluate_one(self, t, y, dy):
        """The rates at (t, y) into ``dy`` on the window with FFTW (``_fused``): the slip into
        the window's box, its static traction out of it (:meth:`WindowedStatic.convolve_one`),
        ``_rates_one``'s numbers without the arrays between."""
        n, c, win = self.n, self.comps[0], self.window
        into_box(y[:n], win.to_box, self.plate[c] * t, win.box_in())
        tau = np.empty(n)
        T = np.empty(self._solve_at.size)
        psi = np.empty(self._solve_at.size)
        spring = self.stiffness * self.plate[c] * t
        _gather_box(win.convolve_one(), win.from_box, spring if self.stiffness else 0.0, self.tau0[c], spring,
                    self._image_at, self._slid, self._solve_at, y[n:], tau, T, psi)
        dy[:] = 0.0
        return self._solve_one(tau, T, psi, dy)

    def _solve_one(self, tau, T, psi, dy):
        """The solve at the points solved (``T``: |tau| there, ``psi``) and its rates scattered
        into ``dy`` (zero where they are not set); ``tau`` less the radiation damping."""
        n, c = self.n, self.comps[0]
        Vh, self.lnV, dph = self.law.slide_rates(T, psi, self._sigma_solved, self.eta, guess=self.lnV, at=self.at)
        V = np.zeros(n)
        _scatter(tau, self._slid, self._solve_of, Vh, dph, self._creep_at, self.plate[c], self.plate_speed, self.eta,
                 dy[:n], dy[n:], V)
        self.last = (V, {c: tau}, {c: dy[:n].copy()})
        return dy

    def error_weights(self):
        """(L, a, the points integrated) at the unknowns' points: the error of the slip is
        scaled by L + |slip|, that of the state by a (an error of a in psi is a factor e in V);
        integrate.error_norm."""
        return self._L, self._a, self.slides


class Fields:
    """The fields of ``system`` at (t, y), ``last`` its evaluation there, each computed when
    asked: ``grid_of(name)`` the field over the grid ({component: field} for "delta", "v",
    "tau"; a field for "psi" and "V"); ``at_of(name, nodes)`` the field ("delta_3", "psi",
    ...) at the flat indices ``nodes`` of the grid; ``peak_of(s1, s3)`` the largest slip rate
    over the grid's nodes [s1, s3] and its node (i, k), the first in the grid's order that
    has it; ``own(name)`` a field at the system's points and ``spread(name, x)`` such a field
    over the grid. On a window the creeping region's values are the plate's and its tau
    needs the grid's transforms. (An object, not closures: closures that call each other make
    a reference cycle at every step, work for the garbage collector.)"""

    __slots__ = ("system", "t", "y", "V", "tau", "v")

    def __init__(self, system, t, y, last):
        self.system, self.t, self.y = system, t, y
        self.V, self.tau, self.v = last

    def own(self, name):
        """The field ``name`` ("delta_3", "psi", "V", or "delta", "v", "tau" as {component:
        field}) at the system's points."""
        kind, _, c = name.partition("_")
        if kind in ("delta", "psi"):
            delta, psi = self.system.split(self.y)
            x = delta if kind == "delta" else psi
        else:
            x = {"v": self.v, "tau": self.tau, "V": self.V}[kind]
        return x[int(c)] if c else x

    def _outside(self, name):
        """The value of the field ``name`` where the plane creeps (NaN: not one value)."""
        kind, _, c = name.partition("_")
        sysm = self.system
        if kind == "delta":
            return sysm.plate[int(c)] * self.t
        if kind == "v":
            return sysm.plate[int(c)]
        return {"psi": 0.0, "V": sysm.plate_speed}.get(kind, np.nan)

    def spread(self, name, x=None):
        """The field ``name`` of one value a node (``x`` at the system's points, or over the
        grid already; None: this point's) over the grid, the plate's values where it creeps."""
        sysm = self.system
        shape = sysm.grid.shape
        x = self.own(name) if x is None else x
        N = int(np.prod(shape))
        if sysm.window is None or x.size == N:
            return x.reshape(shape)
        out = np.full(N, self._outside(name))
        out[sysm.points] = x
        return out.reshape(shape)

    def grid_of(self, name):
        sysm = self.system
        if name == "tau" and sysm.window is not None:
            return self._tau_grid()
        if name in ("delta", "v", "tau"):
            return {c: self.spread(f"{name}_{c}") for c in sysm.comps}
        return self.spread(name)

    def _tau_grid(self):
        sysm = self.system
        shape = sysm.grid.shape
        F = sysm.static.traction(self.grid_of("delta"))
        vg = self.grid_of("v")
        out = {}
        for c in sysm.comps:
            x = (sysm._tau0_grid[c].reshape(shape) + F[c] + sysm.stiffness * sysm.plate[c] * self.t).ravel()
            if sysm.image is not None:
                x = 0.5 * (x + x[sysm._image_grid])
            x -= sysm.eta * vg[c].ravel()
            x[sysm.points] = self.tau[c]
            out[c] = x.reshape(shape)
        return out

    def at_of(self, name, nodes):
        sysm = self.system
        if sysm.window is None:
            return self.own(name)[nodes]
        at, on, every = sysm._places(nodes)
        if every:                                   # every node on the window
            return self.own(name)[at]
        if name.startswith("tau_"):                 # the creeping region's tau: the grid's
            return self._tau_grid()[int(name[4:])].ravel()[nodes]
        return np.where(on, self.own(name)[at], self._outside(name))

    def peak_of(self, s1, s3):
        sysm = self.system
        shape = sysm.grid.shape
        if sysm.window is None:
            Vr = self.V.reshape(shape)[s1, s3]
            k = int(np.argmax(Vr))
            return float(Vr.flat[k]), tuple(int(i) + (sl.start or 0)
                                            for i, sl in zip(np.unravel_index(k, Vr.shape), (s1, s3)))
        inside, first_out = sysm._region(s1, s3)
        m, node = -np.inf, shape[0] * shape[1]
        if inside.size:
            m, node = _largest_at(self.V, inside, sysm.points)
        if first_out >= 0 and (sysm.plate_speed > m or (sysm.plate_speed == m and first_out < node)):
            m, node = sysm.plate_speed, first_out
        return float(m), divmod(int(node), shape[1])


def _locate(points, nodes):
    """(the place in the increasing ``points`` of each of ``nodes``, whether it is there)."""
    at = np.minimum(np.searchsorted(points, nodes), points.size - 1)
    return at, points[at] == nodes


@njit()
def _largest_at(V, inside, points):
    """(the largest of V[inside], points[] of its place): the first largest, as numpy's
    argmax (the first NaN when there is one)."""
    j = 0
    m = V[inside[0]]
    for q in range(inside.size):
        x = V[inside[q]]
        if x != x:
            return x, points[inside[q]]
        if x > m:
            m, j = x, q
    return m, points[inside[j]]


@njit()
def _gather(tau0, F, shift, image, slid, solve_at, psi, tau, T, psi_solved):
    """tau = tau0 + F + shift (made even about the ``image`` of each point when given), and
    at the points solved (``slid[solve_at]``) |tau| into T and psi into psi_solved."""
    for i in range(tau.size):
        tau[i] = tau0[i] + F[i] + shift
    if image.size:
        for i in range(tau.size):
            j = image[i]
            if j > i:
                x = 0.5 * (tau[i] + tau[j])
                tau[i] = x
                tau[j] = x
            elif j == i:
                tau[i] = 0.5 * (tau[i] + tau[i])
    for k in range(solve_at.size):
        i = slid[solve_at[k]]
        T[k] = abs(tau[i])
        psi_solved[k] = psi[i]


@njit()
def _gather_box(box, from_box, spring_out, tau0, spring, image, slid, solve_at, psi, tau, T, psi_solved):
    """_gather of the static traction on the window's ``box`` (window.out_of_box, into tau),
    less ``spring_out`` (the spring's load the window's response leaves out:
    QuasiDynamic.elastic) when it is not zero."""
    out_of_box(box, from_box, tau)
    if spring_out != 0.0:
        for i in range(tau.size):
            tau[i] = tau[i] - spring_out
    _gather(tau0, tau, spring, image, slid, solve_at, psi, tau, T, psi_solved)


@njit()
def _scatter(tau, slid, solve_of, V_solved, dpsi_solved, creep_at, plate, speed, eta, dd, dpsi, V):
    """The rates of the sliding points from their solve (V tau / |tau|), the plate's on the
    creeping ones; tau then less eta times the slip rate (the radiation damping)."""
    for k in range(slid.size):
        i = slid[k]
        v = V_solved[solve_of[k]]
        T = abs(tau[i])
        dd[i] = (v / T) * tau[i] if T > 0 else 0.0
        V[i] = v
        dpsi[i] = dpsi_solved[solve_of[k]]
    for i in creep_at:
        dd[i] = plate
        V[i] = speed
    for i in range(tau.size):
        tau[i] -= eta * dd[i]
