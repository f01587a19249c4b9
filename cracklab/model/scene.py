"""A scene: everything needed to run one simulation, validated at construction."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, check_fields_nesting, check_positive
from .grid import Grid
from ..laws import LAWS, law_parameters
from .loading import Loading
from .material import Material
from .sequence import Sequence
from .record import FIELDS, Record, face_field
from ..solver.interfaces import interface_type
from ..solver.schemes import SCHEMES
from .units import check_scene_units
from ..solver.stability import beta_max, gamma_limit
from ..limits import MAX_FFT_THREADS, MAX_SNAPSHOTS, MAX_STEPS  # noqa: F401  (model.scene.MAX_* as before)

#: {formulation: its convolution rule}, one per time scheme (cracklab.solver.schemes)
FORMULATIONS = {name: scheme.rule for name, scheme in SCHEMES.items()}
MIRROR_ROUNDOFF = 1e-12     # |tau0_3| on the lines of a free surface's mirror, relative to max |tau0_3|
DEFAULT_BETA = 0.5          # a Scene without beta takes min(DEFAULT_BETA, its stable limit)


def resolve_formulation(formulation: str, components, interface=None) -> str:
    """"auto": the paper's displacement scheme when only mode I is active, the product
    scheme (stable in mode II, docs/reference/stability.md) whenever a shear component is; of those,
    with ``interface`` (an interface type, solver/interfaces), a scheme it accepts
    (``auto_scheme``: the product scheme on a pair of different materials). Any other
    value is returned as it is."""
    if formulation != "auto":
        return formulation
    preferred = "product" if any(c in (1, 3) for c in components) else "displacement"
    return preferred if interface is None else interface.auto_scheme(preferred)


def _check_threads(name, value, alternative=""):
    """A thread count: an integer in [1, MAX_FFT_THREADS]."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= MAX_FFT_THREADS:
        raise InputError(name, f"must be {alternative}an integer >= 1 (and <= {MAX_FFT_THREADS}), got {value!r}")


@dataclass(frozen=True)
class Numerics:
    """Scheme options: ``formulation`` "displacement" (Eq. 32, trapezoid pre-integrated
    kernel (46), explicit update (37)) or "velocity" (Eq. 33, discretised kernel (45),
    semi-implicit update (50)) or "product" (velocity formulation with Z integrated
    exactly against the piecewise-linear velocity history, trapezoid update (50), one
    predictor-corrector pass: does not grow in mode II, docs/reference/stability.md) or "product2" (the
    product scheme with the law updated at the step's mean velocity: a slip-weakening front
    converges at second order in dt, docs/reference/stability.md "The order of a rupture front"); "auto" (default):
    product when a shear component is active, displacement otherwise, or the scheme the
    interface runs where it does not run that one (product between two different materials). History ``engine``
    "exponential" (flat cost per step), "direct" (the reference), or "auto" (default:
    exponential, direct when a ``window`` is set); ``window`` truncates the history at
    T = q c_s t (None: full history; a window longer than the run truncates nothing);
    ``rupture_threshold``: a point has failed when its velocity magnitude first exceeds it. ``fft_threads``: threads of the FFTs, and of
    the exponential engine's loop unless ``engine_threads`` is given (the two scale
    differently: docs/studies/performance.md). With two or more engine threads the exponential
    engine advances its recursive states on a thread of its own while the transforms and
    the interface law run; on two cores ``fft_threads=1, engine_threads=2`` is the fastest
    (docs/studies/performance.md)."""

    formulation: str = "auto"
    engine: str = "auto"
    window: float | None = None
    rupture_threshold: float = 0.0
    fft_threads: int = 1
    engine_threads: int | None = None

    def __post_init__(self):
        check_fields_nesting(self, "numerics")
        from ..history import ENGINES

        if not isinstance(self.engine, str) or (self.engine not in ENGINES and self.engine != "auto"):
            raise InputError("numerics.engine",
                             f"must be one of {['auto'] + sorted(ENGINES)}, got {self.engine!r}")
        if not isinstance(self.formulation, str) or \
                (self.formulation not in FORMULATIONS and self.formulation != "auto"):
            raise InputError("numerics.formulation",
                             f"must be one of {('auto',) + tuple(FORMULATIONS)}, got {self.formulation!r}")
        if self.window is not None:
            check_positive("numerics.window", self.window)
            if self.engine != "auto" and not ENGINES[self.engine].windowed:
                windowed = " or ".join(repr(name) for name, cls in ENGINES.items() if cls.windowed)
                raise InputError("numerics.window", f"a truncated history needs engine {windowed} "
                                                    f"(engine {self.engine!r} keeps the whole history)")
        check_positive("numerics.rupture_threshold", self.rupture_threshold, allow_zero=True)
        _check_threads("numerics.fft_threads", self.fft_threads)
        if self.engine_threads is not None:
            _check_threads("numerics.engine_threads", self.engine_threads, "None (as fft_threads) or ")

    @property
    def history_threads(self) -> int:
        """Threads of the history engine's loop: ``engine_threads``, or ``fft_threads`` when None."""
        return int(self.fft_threads if self.engine_threads is None else self.engine_threads)

    def scheme(self, components, interface=None) -> tuple[str, str]:
        """(formulation, convolution rule) used for a scene with these active components
        (and, with ``interface``, this interface type: see ``resolve_formulation``)."""
        formulation = resolve_formulation(self.formulation, components, interface)
        return formulation, FORMULATIONS[formulation]


@dataclass(frozen=True, kw_only=True)
class Scene:
    """One simulation: the half spaces' ``material`` (both sides) or ``materials`` =
    (top, bottom) (top: x2 > 0), the grid, the interface law, the loading, the duration
    ``t_end``, the time-step factor ``beta`` (dt = beta min(dx1, dx3) / c_s; None: the
    stable default), what to record and the numerical options. Validated at construction:
    a bad input raises one InputError naming the field and the accepted range."""

    material: Material | None = None
    grid: Grid
    law: object
    loading: Loading
    t_end: float
    beta: float | None = None
    record: Record = field(default_factory=Record)
    numerics: Numerics = field(default_factory=Numerics)
    units: dict = field(default_factory=lambda: {"length": "1", "time": "1", "stress": "1"})
    name: str = "scene"
    materials: tuple | None = None
    #: {field: where it was read}, for a field read from a file (cracklab.model.field_files):
    #: written as its input variable's ``source`` attribute; not part of the scene's identity
    sources: dict = field(default_factory=dict, compare=False, repr=False)
    #: a sequence of earthquakes (cracklab.model.sequence): the plate's loading and the
    #: adaptive time step; None: one rupture at the fixed step beta
    sequence: Sequence | None = None

    def __post_init__(self):
        check_fields_nesting(self, "")
        self._check_materials()
        for name, cls in (("grid", Grid), ("loading", Loading), ("record", Record), ("numerics", Numerics)):
            if not isinstance(getattr(self, name), cls):
                raise InputError(name, f"must be a cracklab.{cls.__name__}, got {type(getattr(self, name)).__name__}")
        if type(self.law) not in LAWS.values():
            raise InputError("law", f"must be one of the laws {sorted(LAWS)}, got {type(self.law).__name__}")
        if not isinstance(self.name, str):
            raise InputError("name", f"must be a string, got {self.name!r}")
        units = ("length", "time", "stress")
        if not isinstance(self.units, dict) or set(self.units) != set(units) \
                or not all(isinstance(v, str) for v in self.units.values()):
            raise InputError("units", f"must be a dict of strings with exactly the keys {units}, got {self.units!r}")
        check_scene_units(self.units)
        for name in ("t_end", "beta"):
            if isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(name, f"must be a number > 0, got {getattr(self, name)!r}")
        object.__setattr__(self, "t_end", check_positive("t_end", self.t_end))
        if self.beta is not None:
            object.__setattr__(self, "beta", check_positive("beta", self.beta))
        self._check_shapes()
        kind = self.interface_type
        if not kind.accepts_scheme(self.formulation):
            raise InputError("numerics.formulation", kind.scheme_error(self.formulation))
        active = self.components
        if not active:
            raise InputError("loading", f"no load on a component the law {self.law.kind!r} acts on "
                                        f"(law components {self.law.components})")
        if self.loading.constant_K and self.loading.l0 is None \
                and getattr(self.law, "initial_crack", None) is None:
            raise InputError("loading.l0", "must be given (> 0) for constant_K when the law has no initial crack "
                                           "to measure it from")
        for c in self.loading.loaded():
            if c not in self.law.components:
                hint = " (without sigma_n it follows the normal traction tau0_2 + f_2)" \
                    if c == 2 and hasattr(self.law, "follows_normal") else ""
                raise InputError(f"loading.tau0_{c}", f"law {self.law.kind!r} does not act on component {c}{hint}")
        for c in self.law.needs:
            if c not in active:
                raise InputError(f"loading.tau0_{c}", f"must be loaded: law {self.law.kind!r} without sigma_n "
                                                      f"follows the normal traction (tau0_{c} < 0: compression), "
                                                      f"or give law.sigma_n")
        if self.record.fields is None:      # the default: the slip of every active component
            object.__setattr__(self, "record", dataclasses.replace(
                self.record, fields=tuple(f"delta_{c}" for c in active)))
        self.law.check_scene(self)
        if self.sequence is not None:
            if not isinstance(self.sequence, Sequence):
                raise InputError("sequence", f"must be a cracklab.Sequence, got {type(self.sequence).__name__}")
            self.sequence.check_scene(self)
            if self.beta is None:      # the dynamic step's fraction, for the fully dynamic response
                object.__setattr__(self, "beta", min(DEFAULT_BETA, self.beta_max))
        else:
            self._check_steps(kind, active)
        self.record.region_slices(self.grid)
        self.record.station_nodes(self.grid)
        self._check_record_fields(active)

    def _check_steps(self, kind, active):
        """beta within the scheme's stable limit, and the fixed steps and snapshots within bounds."""
        bmax = self.beta_max
        if self.beta is None:  # the default: 0.5, or the stable limit where that is lower
            object.__setattr__(self, "beta", min(DEFAULT_BETA, bmax))
        if self.beta > bmax:
            g, mode = gamma_limit(self.formulation, active, self.grid.plane, self.material.nu)
            raise InputError("beta", f"must be in (0, {bmax:.4f}] for the {self.formulation} scheme at nu = "
                                     f"{self.material.nu:g} on this grid (mode {mode} is stable up to gamma = "
                                     f"q_max c_s dt = {g:.4g}, docs/reference/stability.md"
                                     + kind.margin_note()
                                     + f"), got {self.beta!r}; "
                                     f"without beta a scene takes min({DEFAULT_BETA}, the limit)")
        steps = self.t_end / self.dt
        if not steps <= MAX_STEPS:
            raise InputError("t_end", f"must be at most {MAX_STEPS:.0e} time steps of dt = beta min(dx1, dx3) / cs "
                                      f"= {self.dt:.6g}, i.e. t_end <= {MAX_STEPS * self.dt:.6g}, got {self.t_end!r} "
                                      f"({steps:.3g} steps)")
        if self.nsteps < 1:
            raise InputError("t_end", f"must hold at least one time step, t_end >= dt = beta min(dx1, dx3) / cs "
                                      f"= {self.dt:.6g}, got {self.t_end!r}")
        if self.record.fields and self.record.times is None:
            every = self.record.every or max(1, self.nsteps // 20)
            if self.nsteps // every + 1 > MAX_SNAPSHOTS:
                raise InputError("record.every", f"must give at most {MAX_SNAPSHOTS:.0e} snapshots "
                                                 f"(every >= {self.nsteps // MAX_SNAPSHOTS + 1} for "
                                                 f"{self.nsteps} steps), got {every}")
        self.record.snapshot_steps(self.nsteps, self.dt)

    def _check_record_fields(self, active):
        state = type(self.law).state_variables
        for f in self.record.fields:
            if f in state and self.law.unrecordable(f):
                raise InputError("record.fields", self.law.unrecordable(f))
            if f in state or f == "strength":
                continue
            if face_field(f):
                self._check_face_field(f, face_field(f)[2], active)
                continue
            if f not in FIELDS:
                raise InputError("record.fields", f"{f!r} is not a state variable of the law {self.law.kind!r} "
                                                  f"(its state variables: {', '.join(state) or 'none'})")
            if int(f[-1]) not in active:
                raise InputError("record.fields", f"{f!r} is not computed: active components are {active}")

    def _check_face_field(self, name, c, active):
        """A face's own motion is held on a bimaterial interface, for the components its faces carry."""
        if not self.interface_type.holds_faces:
            raise InputError("record.fields", f"{name!r}: each face's own motion is computed on a bimaterial "
                                              f"interface (materials = (top, bottom), two different materials); "
                                              f"with one material the shear faces move as +-delta/2")
        if self.grid.plane and not ((c == 3 and 3 in active) or (c != 3 and set(active) & {1, 2})):
            raise InputError("record.fields", f"{name!r} is not computed: in the plane problem the faces carry "
                                              f"components 1 and 2 with an in-plane component active, 3 with "
                                              f"the anti-plane one; active components are {active}")

    def _check_materials(self):
        """One material for both sides, or (top, bottom): stored as ``materials`` = (top,
        bottom) always, and ``material`` = the one material, or of two the one with the faster
        shear waves (it sets the time step)."""
        material, materials = self.material, self.materials
        if material is not None and not isinstance(material, Material):
            raise InputError("material", f"must be a cracklab.Material, got {type(material).__name__}")
        if materials is None:
            if material is None:
                raise InputError("material", "is required (or materials = (top, bottom))")
            materials = (material, material)
        else:
            if not isinstance(materials, (tuple, list)) or len(materials) != 2:
                raise InputError("materials", f"must be (top, bottom), two cracklab.Material, got {materials!r}")
            for side, m in zip(("top", "bottom"), materials):
                if not isinstance(m, Material):
                    raise InputError(f"materials.{side}", f"must be a cracklab.Material, got {type(m).__name__}")
            materials = tuple(materials)
            top, bottom = materials
            if material is not None and materials != (material, material) \
                    and material != (bottom if bottom.cs > top.cs else top):  # a scene's own (replace)
                raise InputError("material", "give material (both sides) or materials (top, bottom), not both "
                                             "with different values")
        top, bottom = materials
        object.__setattr__(self, "materials", materials)
        # the time step and the velocity scales follow the side with the faster shear waves
        object.__setattr__(self, "material", bottom if bottom.cs > top.cs else top)

    def _check_shapes(self):
        shape = self.grid.shape
        expected = (f"(n1, n3 + 1) = {shape} (the half plane x3 = 0 .. L3 below the free surface, nodes "
                    f"k dx3, k = 0 .. n3: grid.free_surface)" if self.grid.free_surface else f"(n1, n3) = {shape}")

        def check(name, value, boolean=False):
            if value is None or np.ndim(value) == 0:
                return
            arr = np.asarray(value)
            if arr.shape != shape:
                raise InputError(name, f"field shape must be {expected}, got {arr.shape}")
            if not boolean and arr.dtype != bool and not np.all(np.isfinite(arr) | (arr == np.inf)):
                raise InputError(name, "field values must be finite")

        kinds = type(self.law).parameters()
        for key, value in law_parameters(self.law).items():
            kind = kinds[key][1]
            if kind not in ("field", "mask"):
                continue
            check(f"law.{key}", value, boolean=kind == "mask")
            if kind == "mask" and value is not None and np.asarray(value).dtype != bool:
                raise InputError(f"law.{key}", f"must be a boolean mask, got dtype {np.asarray(value).dtype}")
        for c in (1, 2, 3):
            check(f"loading.tau0_{c}", self.loading.field(c), boolean=True)
        if self.grid.free_surface:
            # odd about the surface x3 = 0 and, by the doubled cell's period, about x3 = L3
            # (to the round-off of an odd expression, e.g. sin(pi x3 / L3) at x3 = L3)
            f3 = np.abs(np.asarray(self.loading.tau0_3, dtype=float))
            lines = f3 if f3.ndim == 0 else f3[:, [0, -1]]
            if np.max(lines) > MIRROR_ROUNDOFF * np.max(f3) * (f3.ndim > 0):
                raise InputError("loading.tau0_3", f"must be 0 on the free surface x3 = 0 and on x3 = L3: tau_3 is odd "
                                                   f"about both lines of the mirror (grid.free_surface), got "
                                                   f"max |tau0_3| = {float(np.max(lines)):g} there"
                                                   + (" (a uniform tau0_3 is not odd: give a field)" if f3.ndim == 0
                                                      else ""))

    @property
    def formulation(self) -> str:
        """The time-stepping scheme actually used (numerics.formulation with "auto" resolved)."""
        return resolve_formulation(self.numerics.formulation, self.components, self.interface_type)

    @property
    def beta_max(self) -> float:
        """Largest stable beta of this scene's scheme, grid and Poisson ratio (cracklab.stability);
        of two different materials, the interface's margin (0.9) times the smaller of the two sides'
        limits (the coupled faces grew at 0.97-1.0 of it: docs/studies/performance.md,
        "Bimaterial interface")."""
        comps = self.components
        scheme = self.numerics.scheme(comps, self.interface_type)
        limit = min(beta_max(self.grid, *scheme, comps, nu=m.nu) for m in set(self.materials))
        return limit * self.interface_type.margin

    @property
    def interface_type(self) -> type:
        """The type of the interface between the scene's two half spaces (solver/interfaces):
        what it accepts, its stability margin."""
        return interface_type(self.materials)

    @property
    def two_materials(self) -> bool:
        """True when the two half spaces differ (the bimaterial interface)."""
        return self.materials[0] != self.materials[1]

    @property
    def dt(self) -> float:
        """Eq. (51): dt = beta min(dx1, dx3) / c_s."""
        return self.beta * self.grid.dx_min / self.material.cs

    @property
    def nsteps(self) -> int:
        """Number of time steps, ceil(t_end / dt)."""
        return int(np.ceil(self.t_end / self.dt - 1e-9))

    @property
    def components(self) -> tuple[int, ...]:
        """Active displacement-discontinuity components: loaded ones the law acts on,
        plus both shear components in 3D (modes II and III couple there)."""
        active = set(self.loading.loaded()) & set(self.law.components)
        if not self.grid.plane and active & {1, 3}:
            active |= {1, 3}
        return tuple(sorted(active))

    def replace(self, **changes) -> "Scene":
        """A new scene with ``changes``, validated like any other (a new ``material``
        replaces both sides; new ``materials`` replace the one material)."""
        if "material" in changes and "materials" not in changes:
            changes["materials"] = None
        elif "materials" in changes and "material" not in changes:
            changes["material"] = None
        if "sources" not in changes:  # a replaced law or loading no longer holds what was read
            changes["sources"] = {k: v for k, v in self.sources.items() if k.split(".")[0] not in changes}
        return dataclasses.replace(self, **changes)

    # thin wrappers over cracklab.model.scene_io (lossless round trips, see docs/reference/scenes.md)
    def to_dataset(self):
        """The scene as an xarray Dataset (a lossless round trip through ``Scene.from_dataset``)."""
        from .scene_io import scene_to_dataset

        return scene_to_dataset(self)

    def to_toml(self, path=None) -> str | Path:
        """The scene as TOML: the text, or with ``path`` the file, its fields in one netCDF
        sidecar next to it. Without ``path``: the TOML text, every field inline as nested
        lists. With ``path``: the scalars written to that TOML file and every field into
        ``<stem>.fields.nc`` beside it, referenced from the TOML; returns the path. Both
        round trips through ``Scene.from_toml`` are lossless (docs/reference/scenes.md, docs/reference/toml.md)."""
        from .scene_io import scene_to_toml, write_scene_toml

        return scene_to_toml(self) if path is None else write_scene_toml(self, path)

    @staticmethod
    def from_dataset(ds) -> "Scene":
        """The scene of a Dataset written by ``to_dataset`` or by a run."""
        from .scene_io import scene_from_dataset

        return scene_from_dataset(ds)

    @staticmethod
    def from_toml(source, *, base=None, allow=()) -> "Scene":
        """The scene of a TOML text, a file's bytes, or a TOML file. A file is a
        ``pathlib.Path`` or a one-line string ending in ".toml". A field's file reference ``{ file = "x.nc",
        var = "tau_c" }`` is read relative to the file's directory (for text: ``base``,
        default the current directory), from that folder and below or the ``allow`` folders,
        and checked against the grid (docs/reference/toml.md)."""
        from .scene_io import scene_from_toml

        return scene_from_toml(source, base=base, allow=allow)
