"""The description of a fabric: architecture, yarns, tiling, periodicity.

Axes: warp (and binder) yarns run along x, weft yarns along y, z is the
thickness, the fabric's mid-plane is z = 0 and the unit cell starts at x = y = 0.

* 2D weave (:class:`~fabmd.geometry.weave.Weave`, matrix ``(n_warp, n_weft)``):
  warp *i* lies at y = (i + ½)·warp spacing, weft *j* at x = (j + ½)·weft
  spacing; unit cell ``n_weft·s_weft × n_warp·s_warp``. At every crossing the
  two yarns' centrelines are (h_warp + h_weft)/2 + clearance apart, each
  displaced half of that from the mid-plane (both families crimp). A height here is
  the one the yarn's virtual fibres fill (``YarnSpec.occupied_height_m``: the
  section's, or more where ``fibre_packing = "area"`` pokes out of a thin section),
  so the clearance is the gap between the crossing yarns' fibres.
* 3D (:class:`~fabmd.geometry.architecture3d.Architecture3D`): straight weft
  layers and stuffer warps, binders weaving between the gaps; unit cell
  ``columns·s_weft × dents·s_warp``. Neighbouring weft layers and gap levels
  are (their heights)/2 + clearance apart; a gap is as high as the tallest yarn
  that passes through it.

:meth:`Fabric.yarn_paths` gives every yarn centreline of the tile.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from .. import inputs
from ..errors import InputError
from ..units import TEX, quantity
from .architecture3d import Architecture3D
from .overrides import YarnOverride
from .paths import YarnPath
from .section import section_height
from .unit_cell import layered_cell, layered_levels, woven_cell
from .weave import Weave
from .yarn_spec import (  # noqa: F401 - YarnSpec and its limits, also by this module's name
    AREAL_DENSITY_TOLERANCE,
    FILAMENT_TOLERANCE,
    MAX_DATASHEET_CRIMP,
    PACKING_LIMIT,
    YarnSpec,
)

FAMILIES = ("warp", "weft", "binder")
#: direction each family runs along (0 = x, 1 = y)
FAMILY_AXIS = {"warp": 0, "weft": 1, "binder": 0}


@dataclass(frozen=True)
class Fabric:
    """A woven fabric, ready to render into beads.

    Args:
        architecture: a 2D :class:`Weave` or a 3D :class:`Architecture3D`.
        warp, weft: yarn families (spacing required).
        binder: binder yarns (3D only; their spacing is the warp spacing).
        tiling: unit cells along x (warp direction) and y.
        periodic: periodic in x and y (every yarn continuous across the boundary).
        clearance_m: gap left between crossing yarns' fibres [m]; default 10 %
            of the smallest yarn height.
        plateau: fraction of a crossed yarn's half-width over which a crimped
            yarn stays level, in [0, 1) (0: pure cosine waves).
        areal_density_kg_m2: datasheet areal density [kg/m²] (accepts "200 g/m2");
            checked against the straight yarns' mass Σ tex·count (it may exceed it
            by the crimp, at most :data:`MAX_DATASHEET_CRIMP`, and fall short by at
            most :data:`AREAL_DENSITY_TOLERANCE`) and reported against the built one.
        thickness_m: datasheet thickness [m] (stored and reported; calibration uses it).
        thickness_pressure_pa: the pressure the thickness is quoted at [Pa].
        auto_clearance: choose the loose state for a dense fabric (scene files:
            ``clearance_m = "auto"``): the build lifts crossing yarns (and 3D levels) apart
            (``lift_m``, growing per try) until no yarns overlap (the crimp stage
            compacts them again). With it, or for yarns sized from a
            ``fibre_volume_fraction``, 2D yarns wider than their spacing less the
            clearance are built narrower and taller (same section area; the crimp
            stage spreads them); ``woven_width_m`` keeps the width given.
        lift_m: extra separation through the thickness between crossing yarns
            (2D) or neighbouring levels (3D) of the loose state [m], on top of the
            clearance.
        overrides: :class:`~fabmd.geometry.overrides.YarnOverride` list: other yarn
            specs for some yarns (by position) or layers (3D) of a family. Their
            sections set the crossings (2D) and the level heights (3D); their tex the
            mass. Spec keys: the family name, ``"<family>:<k>"`` for override k (from 1).
    """

    architecture: Weave | Architecture3D
    warp: YarnSpec
    weft: YarnSpec
    binder: YarnSpec | None = None
    tiling: tuple = (1, 1)
    periodic: bool = False
    clearance_m: float | None = None
    plateau: float = 0.5
    areal_density_kg_m2: float | None = None
    thickness_m: float | None = None
    thickness_pressure_pa: float | None = None
    auto_clearance: bool = False
    lift_m: float = 0.0
    overrides: tuple = ()
    #: per family, the width given for the woven yarn where the loose one is narrower [m]
    woven_width_m: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        arch = self.architecture
        if not isinstance(arch, Weave | Architecture3D):
            raise InputError(f"fabric.architecture must be a Weave or an Architecture3D, "
                             f"got {type(arch).__name__}")
        for fam in ("warp", "weft"):
            spec = getattr(self, fam)
            if not isinstance(spec, YarnSpec):
                raise InputError(f"fabric.{fam} must be a YarnSpec, got {spec!r}")
            if spec.spacing_m is None:
                raise InputError(f"yarns.{fam} needs spacing_m (or count_per_m)")
        if self.is_3d:
            if not isinstance(self.binder, YarnSpec):
                raise InputError(f"fabric.binder (yarns.binder) is required: the 3D "
                                 f"architecture has {arch.n_binders} binder yarns")
            pitch = self.binder_pitch_m()
            if self.binder.spacing_m is not None and not math.isclose(
                    self.binder.spacing_m, pitch, rel_tol=1e-9):
                raise InputError(f"yarns.binder.spacing_m = {self.binder.spacing_m:g} m must "
                                 f"equal the binder plane pitch {pitch:g} m (the warp spacing "
                                 f"{self.warp.spacing_m:g} m over the binder planes per dent "
                                 f"+ 1 when separate) or be left out")
        elif self.binder is not None:
            raise InputError("fabric.binder (yarns.binder) is only used by 3D architectures")
        tiling = self.tiling
        if not isinstance(tiling, list | tuple) or len(tiling) != 2:
            raise InputError(f"fabric.tiling must be two integers [along x, along y], "
                             f"got {tiling!r}")
        object.__setattr__(self, "tiling", (inputs.positive_int("fabric.tiling[0]", tiling[0]),
                                            inputs.positive_int("fabric.tiling[1]", tiling[1])))
        if not isinstance(self.periodic, bool):
            raise InputError(f"fabric.periodic must be true or false, got {self.periodic!r}")
        if isinstance(self.clearance_m, str) and self.clearance_m.strip() == "auto":
            object.__setattr__(self, "auto_clearance", True)
            object.__setattr__(self, "clearance_m", None)
        if not isinstance(self.auto_clearance, bool):
            raise InputError(f"fabric.auto_clearance must be true or false, "
                             f"got {self.auto_clearance!r}")
        if self.clearance_m is None:
            object.__setattr__(self, "clearance_m",
                               0.1 * min(s.height_m for s in self.specs().values()))
        else:
            object.__setattr__(self, "clearance_m", inputs.non_negative(
                "fabric.clearance_m", quantity(self.clearance_m, "length",
                                               "fabric.clearance_m")))
        inputs.in_range("fabric.plateau", self.plateau, 0.0, 1.0, high_open=True)
        object.__setattr__(self, "lift_m", inputs.non_negative(
            "fabric.lift_m", quantity(self.lift_m, "length", "fabric.lift_m")))
        object.__setattr__(self, "woven_width_m", dict(self.woven_width_m))  # own copy
        self._check_overrides()
        self._datasheet()
        if not self.is_3d:
            self._narrow_loose_yarns()
        self._check_fit()

    def _datasheet(self) -> None:
        for name, kind in (("areal_density_kg_m2", "areal_density"), ("thickness_m", "length"),
                           ("thickness_pressure_pa", "pressure")):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, inputs.positive(
                    f"fabric.{name}", quantity(value, kind, f"fabric.{name}")))
        if self.thickness_pressure_pa is not None and self.thickness_m is None:
            raise InputError("fabric.thickness_pressure_pa is given without "
                             "fabric.thickness_m")
        target = self.areal_density_kg_m2
        if target is None:
            return
        parts = self.straight_areal_density_kg_m2()
        straight = sum(parts.values())
        crimp = target / straight - 1.0
        length = self._length_per_area()
        terms = " + ".join(
            f"{fam} {parts[fam] / length[fam] / TEX:.4g} tex x {length[fam]:.4g} m/m² "
            f"= {1e3 * parts[fam]:.4g} g/m²" for fam in parts)
        if crimp < -AREAL_DENSITY_TOLERANCE or crimp > MAX_DATASHEET_CRIMP:
            why = ("lighter than its straight yarns" if crimp < 0 else
                   f"heavier than its straight yarns by more than "
                   f"{100 * MAX_DATASHEET_CRIMP:.0f} % crimp")
            raise InputError(
                f"fabric datasheet is inconsistent: areal density {1e3 * target:.4g} g/m² is "
                f"{why}: {terms}, total {1e3 * straight:.4g} g/m² (implied mean crimp "
                f"{100 * crimp:+.1f} %); check tex, ends/picks per cm and areal density")

    def with_loose_width(self, factor: float) -> Fabric:
        """The same fabric with warp and weft ``factor`` × as wide and as much taller (same
        section area) in the loose state; ``woven_width_m`` keeps the given widths. In 3D
        fabrics the binders keep theirs: narrower weft columns leave them room to pass."""
        if factor == 1.0:
            return self

        def narrower(spec: YarnSpec) -> YarnSpec:
            width = factor * spec.width_m
            return dataclasses.replace(
                spec, width_m=width, fibre_volume_fraction=None,
                height_m=section_height(spec.section.area_m2, width, spec.shape))

        specs = {fam: narrower(getattr(self, fam)) for fam in ("warp", "weft")}
        woven = {k: self.woven_width_m.get(k, s.width_m)
                 for k, s in self.yarn_spec_table().items()}
        over = tuple(dataclasses.replace(o, spec=narrower(o.spec)) for o in self.overrides)
        return dataclasses.replace(self, woven_width_m=woven, overrides=over, **specs)

    def straight_areal_density_kg_m2(self) -> dict[str, float]:
        """Per family, the mass per fabric area of its yarns laid straight, Σ tex·count [kg/m²]."""
        lx, ly = self.unit_cell_m
        table = self.yarn_spec_table()
        out = dict.fromkeys(self.specs(), 0.0)
        for path, key in zip(*self._unit_cell(), strict=True):
            along = lx if path.axis == 0 else ly
            out[path.family] += table[key].linear_density_kg_m * along / (lx * ly)
        return out

    def _length_per_area(self) -> dict[str, float]:
        lx, ly = self.unit_cell_m
        counts = self.yarns_per_unit_cell()
        return {fam: counts[fam] * (lx if FAMILY_AXIS[fam] == 0 else ly) / (lx * ly)
                for fam in self.specs()}

    def _narrow_loose_yarns(self) -> None:
        c = self.clearance_m

        def narrowed(key: str, spec: YarnSpec) -> YarnSpec:
            room = spec.spacing_m - c
            sized = spec.fibre_volume_fraction is not None or key in self.woven_width_m
            if spec.width_m <= room * (1 + 1e-12) or not (self.auto_clearance or sized):
                return spec
            if room <= 0:
                raise InputError(f"yarns.{key}: the clearance {c:g} m leaves no room in its "
                                 f"spacing {spec.spacing_m:g} m")
            height = section_height(spec.section.area_m2, room, spec.shape)
            self.woven_width_m.setdefault(key, spec.width_m)
            return dataclasses.replace(spec, width_m=room, height_m=height,
                                       fibre_volume_fraction=None)

        for fam in ("warp", "weft"):
            object.__setattr__(self, fam, narrowed(fam, getattr(self, fam)))
        object.__setattr__(self, "overrides", tuple(
            dataclasses.replace(o, spec=narrowed(f"{o.family}:{k}", o.spec))
            for k, o in enumerate(self.overrides, start=1)))

    def _check_overrides(self) -> None:
        overrides = self.overrides
        if isinstance(overrides, YarnOverride):
            overrides = (overrides,)
        if not isinstance(overrides, list | tuple) or not all(
                isinstance(o, YarnOverride) for o in overrides):
            raise InputError(f"fabric.overrides must be a list of YarnOverride, "
                             f"got {overrides!r}")
        object.__setattr__(self, "overrides", tuple(overrides))
        a = self.architecture
        for k, o in enumerate(self.overrides, start=1):
            where = f"yarns.{o.family}.overrides[{k}]"
            base = getattr(self, o.family)
            if base is None or o.family not in self.specs():
                raise InputError(f"{where}: this fabric has no {o.family} yarns")
            if o.spec.spacing_m is not None and not math.isclose(
                    o.spec.spacing_m, base.spacing_m or self.spacing(o.family), rel_tol=1e-9):
                raise InputError(f"{where}: spacing {o.spec.spacing_m:g} m differs from the "
                                 f"family's {self.spacing(o.family):g} m (an override changes "
                                 f"the yarn, not where it lies)")
            if self.is_3d:
                n = {"warp": a.dents, "weft": a.columns, "binder": a.dents}[o.family]
                layers = {"warp": a.warp_gaps,
                          "weft": tuple(range(1, a.weft_layers + 1))}.get(o.family, ())
            else:
                if o.layers:
                    raise InputError(f"{where}: layers are for 3D fabrics; a 2D weave "
                                     f"chooses yarns by position (yarns = [...])")
                n, layers = {"warp": a.n_warp, "weft": a.n_weft}[o.family], ()
            if o.yarns and max(o.yarns) > n:
                raise InputError(f"{where}: yarns {list(o.yarns)} must be positions 1..{n} "
                                 f"in the unit cell")
            bad = [v for v in o.layers if v not in layers]
            if bad:
                kind = "warp gaps (warp_gaps)" if o.family == "warp" else "weft layers"
                raise InputError(f"{where}: layers {bad} are not among the {kind} "
                                 f"{list(layers)}")

    def yarn_spec_table(self) -> dict[str, YarnSpec]:
        """Every yarn spec of the fabric by key: the families present (``specs()``) and
        ``"<family>:<k>"`` for override k (from 1)."""
        out = dict(self.specs())
        for k, o in enumerate(self.overrides, start=1):
            out[f"{o.family}:{k}"] = o.spec
        return out

    def _spec_key(self, family: str, position: int, layer: int | None) -> str:
        key = family
        for k, o in enumerate(self.overrides, start=1):
            if o.matches(family, position, layer):
                key = f"{family}:{k}"
        return key

    def _family_specs(self, family: str) -> list[YarnSpec]:
        return [s for k, s in self.yarn_spec_table().items() if k.split(":")[0] == family]

    def cell_spec_keys(self) -> list[str]:
        """The yarn spec key of every unit-cell yarn, by ``YarnPath.cell_index``."""
        return self._unit_cell()[1]

    def spec_of(self, path: YarnPath) -> YarnSpec:
        """The yarn spec of a yarn of :meth:`yarn_paths` (or :meth:`unit_cell_paths`)."""
        return self.yarn_spec_table()[self.cell_spec_keys()[path.cell_index]]

    # -- derived -----------------------------------------------------------------------
    @property
    def is_3d(self) -> bool:
        return isinstance(self.architecture, Architecture3D)

    def specs(self) -> dict[str, YarnSpec]:
        """Yarn spec of every family that has yarns, in family order."""
        out = {"warp": self.warp, "weft": self.weft}
        if self.is_3d:
            if not self.architecture.warp_gaps:
                del out["warp"]
            out["binder"] = self.binder
        return out

    @property
    def families(self) -> tuple[str, ...]:
        return tuple(self.specs())

    @property
    def unit_cell_m(self) -> tuple[float, float]:
        """Unit-cell size (x, y) [m]."""
        a = self.architecture
        if self.is_3d:
            return a.columns * self.weft.spacing_m, a.dents * self.warp.spacing_m
        return a.n_weft * self.weft.spacing_m, a.n_warp * self.warp.spacing_m

    @property
    def size_m(self) -> tuple[float, float]:
        """Size of the tile (x, y) [m]."""
        lx, ly = self.unit_cell_m
        return lx * self.tiling[0], ly * self.tiling[1]

    def max_binders_per_dent(self) -> int:
        """3D: most binders in one dent (0 in 2D)."""
        return max((len(d) for d in self.architecture.binder_paths), default=0) \
            if self.is_3d else 0

    def binder_pitch_m(self) -> float:
        """3D: distance between neighbouring binder planes [m] (the warp spacing when a
        dent's binders share a plane; over (binders per dent + 1) when separate)."""
        if self.is_3d and self.architecture.separate_binders:
            return self.warp.spacing_m / (self.max_binders_per_dent() + 1)
        return self.warp.spacing_m

    def spacing(self, family: str) -> float:
        """Distance between neighbouring yarns of a family [m] (binder: the dent pitch)."""
        return self.warp.spacing_m if family == "binder" else getattr(self, family).spacing_m

    def yarns_per_unit_cell(self) -> dict[str, int]:
        a = self.architecture
        if self.is_3d:
            counts = {"warp": a.n_warp, "weft": a.n_weft, "binder": a.n_binders}
        else:
            counts = {"warp": a.n_warp, "weft": a.n_weft}
        return {f: n for f, n in counts.items() if n}

    def _check_fit(self) -> None:
        c = self.clearance_m
        # the widest yarn of a family stands for all (overrides may be wider)
        widest = {f: max(self._family_specs(f), key=lambda s: s.width_m) for f in self.specs()}
        weft = widest["weft"]
        warp = widest.get("warp", self.warp)
        binder = widest.get("binder")
        if weft.width_m + c > weft.spacing_m * (1 + 1e-12):
            raise InputError(f"yarns.weft.width_m = {weft.width_m:g} m plus the clearance "
                             f"{c:g} m does not fit the weft spacing {weft.spacing_m:g} m: "
                             f"neighbouring weft yarns would overlap; reduce the width or "
                             f"increase the spacing")
        if self.is_3d and self.architecture.separate_binders:
            room = self.binder_pitch_m()
            need = max(0.5 * (warp.width_m + binder.width_m),
                       binder.width_m) + c
            if need > room * (1 + 1e-12):
                raise InputError(
                    f"binder planes lie {room:g} m apart (warp spacing {self.warp.spacing_m:g} "
                    f"m over {self.max_binders_per_dent() + 1}): stuffers "
                    f"({warp.width_m:g} m wide) and binders ({binder.width_m:g} m "
                    f"wide) need {need:g} m with the clearance: increase yarns.warp.spacing_m "
                    f"or reduce the widths")
        elif self.is_3d:
            room = 0.5 * self.warp.spacing_m
            need = 0.5 * (warp.width_m + binder.width_m) + c
            if need > room * (1 + 1e-12):
                raise InputError(
                    f"stuffer warps ({warp.width_m:g} m wide) and binders "
                    f"({binder.width_m:g} m wide) alternate every half warp spacing "
                    f"({room:g} m) and need {need:g} m with the clearance: increase "
                    f"yarns.warp.spacing_m or reduce the widths")
        elif warp.width_m + c > self.warp.spacing_m * (1 + 1e-12):
            raise InputError(f"yarns.warp.width_m = {warp.width_m:g} m plus the clearance "
                             f"{c:g} m does not fit the warp spacing {self.warp.spacing_m:g} m: "
                             f"neighbouring warp yarns would overlap; reduce the width or "
                             f"increase the spacing")

    # -- geometry ------------------------------------------------------------------------
    def levels(self) -> dict[str, list[float]]:
        """3D: z of every weft layer (``"weft"``) and gap (``"gap"``) [m]; 2D: crossing offsets."""
        c = self.clearance_m + self.lift_m  # the lift dilates the loose state in z
        if not self.is_3d:
            half = 0.25 * (self.warp.occupied_height_m + self.weft.occupied_height_m) + 0.5 * c
            return {"crossing_half_separation": [half]}
        return layered_levels(self, c)

    def unit_cell_paths(self) -> list[YarnPath]:
        """Centrelines of the yarns of one unit cell (length = one period)."""
        return self._unit_cell()[0]

    def _unit_cell(self) -> tuple[list[YarnPath], list[str]]:
        """Unit-cell centrelines and the yarn spec key of each."""
        out, keys = woven_cell(self) if not self.is_3d else layered_cell(self)
        paths = [YarnPath(y.name, y.family, y.axis, y.offset_m, y.length_m, y.period_m,
                          y.node_u_m, y.node_z_m, y.plateau_m, y.z_m, y.level, k)
                 for k, y in enumerate(out)]
        return paths, keys

    def yarn_paths(self) -> list[YarnPath]:
        """Every yarn of the tile, ordered by family, then position, then from the top.

        Names are ``<family>-<n>`` numbered from 1 in that order.
        """
        lx, ly = self.unit_cell_m
        nx, ny = self.tiling
        tiled = []
        for y in self.unit_cell_paths():
            if y.axis == 0:
                copies, step, length = ny, ly, nx * lx
            else:
                copies, step, length = nx, lx, ny * ly
            base = YarnPath(y.name, y.family, y.axis, y.offset_m, length, y.period_m,
                            y.node_u_m, y.node_z_m, y.plateau_m, y.z_m, y.level, y.cell_index)
            tiled += [base.translated(y.name, k * step) for k in range(copies)]
        order = {f: i for i, f in enumerate(FAMILIES)}

        def top(y: YarnPath) -> float:
            return -(max(y.node_z_m) if y.node_z_m else y.z_m)

        tiled.sort(key=lambda y: (order[y.family], round(y.offset_m, 12),
                                  y.cell_index if y.family == "binder" else 0, top(y)))
        count = dict.fromkeys(FAMILIES, 0)
        named = []
        for y in tiled:
            count[y.family] += 1
            named.append(y.translated(f"{y.family}-{count[y.family]}", 0.0))
        return named
