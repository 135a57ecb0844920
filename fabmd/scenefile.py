"""Scene files: a TOML description of a fabric (and of the tests run on it).

Sections fabmd owns (unknown keys in them are refused, naming the key)::

    title = "..."                      # optional
    [fabric]         architecture and its pattern, tiling, periodic, clearance_m, plateau
    [yarns.warp]     YarnSpec fields: material, linear_density_tex, width_m, height_m,
    [yarns.weft]       n_fibres, spacing_m or count_per_m, name, shape,
                       fibre_volume_fraction, filament_diameter_m, filament_count,
                       fibre_packing, bending_stiffness_nm2 (N·m² or "filaments")
    [yarns.binder]   (3D architectures only)
    [materials.NAME] FibreMaterial fields: modulus_pa, density_kg_m3
    [discretisation] Discretisation fields: spacing_ratio, mass_scaling, bending_factor,
                       bead_register ("aligned" | "staggered")
    [contact]        ContactModel fields: friction, normal, normal_stiffness_pa, ...

Every other top-level table (``[crimp]``, ``[tension]``, ``[picture_frame]``,
``[drape]``, ...) is kept as a raw dict in :attr:`Scene.protocols` for the
stage that reads it; :func:`fabmd.preflight.check_scene` builds them all before any
stage runs (``fabmd build`` too). Every table, owned or not, is built by the one
schema builder :func:`fabmd.schema.build` (field types from the classes' annotations,
units declared per field, never guessed from a name). Quantities may carry units as
text: ``"1200 tex"``, ``"2 mm"``, ``"73 GPa"``, ``"4 ends/cm"``, ``"5 N/m"``; bare
numbers are SI (tex for linear density). ``[fabric] architecture`` is one of:

=====================  ===========================================================
``plain``              —
``twill``              ``up``, ``down`` (default 2, 2), ``shift`` (1)
``satin``              ``n`` (5), ``move`` (smallest allowed)
``basket``             ``n``, ``m`` (2, n)
``matrix``             ``matrix`` (rows = warp yarns, 1 = warp on top), ``allow_floats``
``orthogonal``         ``weft_layers``, ``float_columns``, ``dents``, ``columns``, ``warp_gaps``,
                       ``binder_every``
``layer_to_layer``     ``weft_layers``, ``depth``, ``step``, ``dents``, ``columns`` (any),
                       ``warp_gaps``, ``binder_every``
``through_thickness``  ``weft_layers``, ``step``, ``dents``, ``columns`` (any),
                       ``warp_gaps``, ``binders`` (per dent, side by side),
                       ``binder_every`` (binders in every n-th dent)
``binder_paths``       ``weft_layers``, ``binder_paths`` (per dent, per binder, gap per
                       column), ``warp_gaps``, ``allow_floats``, ``separate_binders``
=====================  ===========================================================

plus, for all: ``tiling = [nx, ny]``, ``periodic``, ``clearance_m`` (a length or
``"auto"``: fabmd picks the loose state of a dense fabric), ``plateau``.

A fabric can be described from its **datasheet**: ``[fabric]`` may give
``areal_density_kg_m2`` ("200 g/m2"), ``thickness = "0.25 mm at 4.14 kPa"`` (or
``thickness_m`` and ``thickness_pressure_pa``), ``ends_per_m`` and ``picks_per_m``
("5 ends/cm": the warp and weft counts, instead of the yarns' ``count_per_m``); a
yarn gives its tex, its material's fibre density, optionally ``filament_diameter_m``
and ``filament_count`` ("3K"), ``width_m`` (default: its spacing), ``shape`` and the
``fibre_volume_fraction`` its section is sized for (its height then follows). The
datasheet is checked (filament area, areal density against Σ tex·count) and the build
reports its areal density against it.
Some yarns of a family may differ (a heavier warp yarn, heavier stuffers in the
middle layers): ``[[yarns.<family>.overrides]]`` tables give ``yarns`` (positions in
the unit cell from 1: warp/weft number in 2D, dent or column in 3D) and/or ``layers``
(3D: stuffer gaps as in ``warp_gaps``, weft layers from 1 at the top) and the
``[yarns.<family>]`` keys that change; the others are taken from the family's table (a
section sized by ``fibre_volume_fraction`` follows the override's tex)::

    [[yarns.warp.overrides]]
    yarns = [2]
    linear_density_tex = "1200 tex"

The same objects can be built in Python (:class:`~fabmd.geometry.fabric.Fabric`,
:class:`Scene`).
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from . import schema
from .errors import InputError
from .geometry.architecture3d import Architecture3D
from .geometry.fabric import Fabric, YarnSpec
from .geometry.overrides import YarnOverride
from .geometry.weave import Weave
from .model.beads import Discretisation
from .model.contact import ContactModel
from .model.material import CARBON, GLASS, FibreMaterial

#: materials a scene may name without a [materials.NAME] section
BUILTIN_MATERIALS = {"glass": GLASS, "carbon": CARBON}

def _plain() -> Weave:
    return Weave.plain()


def _matrix(matrix=None, allow_floats: bool = False) -> Weave:
    if matrix is None:
        raise InputError("architecture 'matrix' needs matrix = [[...], ...] (rows = warp "
                         "yarns, 1 = warp on top)")
    return Weave.from_matrix(matrix, allow_floats=allow_floats)


def _binder_paths(weft_layers=None, binder_paths=None, warp_gaps=None,
                  allow_floats: bool = False, separate_binders: bool = False) -> Architecture3D:
    if weft_layers is None or binder_paths is None:
        raise InputError("architecture 'binder_paths' needs weft_layers and binder_paths "
                         "(per dent, per binder, its gap at every weft column)")
    return Architecture3D(weft_layers, binder_paths, warp_gaps, name="3D (binder paths)",
                          allow_floats=allow_floats, separate_binders=separate_binders)


#: architecture -> (constructor, keys it takes)
ARCHITECTURES = {
    "plain": (_plain, ()),
    "twill": (Weave.twill, ("up", "down", "shift")),
    "satin": (Weave.satin, ("n", "move")),
    "basket": (Weave.basket, ("n", "m")),
    "matrix": (_matrix, ("matrix", "allow_floats")),
    "orthogonal": (Architecture3D.orthogonal,
                   ("weft_layers", "float_columns", "dents", "columns", "warp_gaps",
                    "binder_every")),
    "layer_to_layer": (Architecture3D.layer_to_layer,
                       ("weft_layers", "depth", "step", "dents", "columns", "warp_gaps",
                        "binder_every")),
    "through_thickness": (Architecture3D.through_thickness,
                          ("weft_layers", "step", "dents", "columns", "warp_gaps", "binders",
                           "binder_every")),
    "binder_paths": (_binder_paths,
                     ("weft_layers", "binder_paths", "warp_gaps", "allow_floats",
                      "separate_binders")),
}
FABRIC_KEYS = ("architecture", "tiling", "periodic", "clearance_m", "plateau")
#: datasheet keys of [fabric] (see the module docstring)
DATASHEET_KEYS = ("areal_density_kg_m2", "thickness", "thickness_m", "thickness_pressure_pa",
                  "ends_per_m", "picks_per_m")
OWNED = ("fabric", "yarns", "materials", "discretisation", "contact")
TOP_LEVEL_KEYS = ("title", "description")
YARN_FAMILIES = ("warp", "weft", "binder")


@dataclass
class Scene:
    """A loaded scene: the fabric, how it is discretised, contact, and protocol sections.

    Attributes:
        fabric: the fabric description.
        discretisation: bead spacing ratio, mass scaling, bending.
        contact: fibre–fibre contact.
        materials: materials by name (built-ins and ``[materials.NAME]``).
        protocols: raw dicts of every other top-level table (``protocols["crimp"]``).
        title: optional label.
        source: the file it came from (None when built in Python).
    """

    fabric: Fabric
    discretisation: Discretisation = field(default_factory=Discretisation)
    contact: ContactModel = field(default_factory=ContactModel)
    materials: dict = field(default_factory=dict)
    protocols: dict = field(default_factory=dict)
    title: str = ""
    source: str | None = None
    #: ``[contact]`` as given (None when built in Python): rebuilt on a new fibre
    contact_table: dict | None = field(default=None, repr=False, compare=False)

    def model(self, check: bool = True):
        """Render the fabric into a :class:`~fabmd.model.bead_model.BeadModel`."""
        from .model.fabric_model import render_fabric

        return render_fabric(self.fabric, self.discretisation, check=check)

    def with_fibres(self, n_fibres: int) -> Scene:
        """This scene with ``n_fibres`` virtual fibres in every yarn family (tex, counts and
        s/d unchanged); see :meth:`rediscretised`."""
        return self.rediscretised(n_fibres=n_fibres)

    def rediscretised(self, n_fibres: int | None = None,
                      spacing_ratio: float | None = None) -> Scene:
        """This scene with ``n_fibres`` virtual fibres in every yarn family and bead spacing
        ratio ``spacing_ratio`` (None: as it is; tex and counts unchanged). A contact
        derived from a compaction law (``within_family``, ``compaction``) is derived again
        for the new virtual fibre: the law is the yarn's, its pair forces the fibre's."""
        fabric, disc = self.fabric, self.discretisation
        if n_fibres is not None:
            # YarnSpec keeps both its count and the spacing derived from it; pass one
            specs = {fam: dataclasses.replace(spec, n_fibres=n_fibres, spacing_m=None
                                              if spec.count_per_m else spec.spacing_m)
                     for fam, spec in fabric.specs().items()}
            fabric = dataclasses.replace(fabric, **specs)
        if spacing_ratio is not None:
            disc = dataclasses.replace(disc, spacing_ratio=spacing_ratio)
        return self._with(fabric, disc, "rediscretised", changed=n_fibres is not None,
                          what=f"{n_fibres} fibres per yarn")

    def with_yarn_heights(self, heights_m: dict[str, float]) -> Scene:
        """This scene with the loose section of each named family ``heights_m[family]``
        high (m; width, tex and count unchanged, so the yarn's packing changes); the
        contact is derived again where a compaction law makes it depend on the virtual
        fibre's diameter (which follows the section). Families with overrides are
        refused: which of their yarns would change is not clear."""
        specs = self.fabric.specs()
        unknown = set(heights_m) - set(specs)
        if unknown:
            raise InputError(f"Scene.with_yarn_heights: the fabric has no families "
                             f"{sorted(unknown)} (it has {list(specs)})")
        over = sorted({o.family for o in self.fabric.overrides} & set(heights_m))
        if over:
            raise InputError(f"the loose height of {over} cannot be changed alone: their "
                             f"yarns have [[yarns.<family>.overrides]]; give the height in "
                             f"each override instead")
        new = {fam: dataclasses.replace(specs[fam], height_m=float(h),
                                        fibre_volume_fraction=None)
               for fam, h in heights_m.items()}
        fabric = dataclasses.replace(self.fabric, **new)
        return self._with(fabric, self.discretisation, "with_yarn_heights", changed=True,
                          what="the new section")

    def _with(self, fabric: Fabric, disc: Discretisation, caller: str, changed: bool,
              what: str) -> Scene:
        """This scene with ``fabric`` and ``disc``, the contact derived again from its
        table where a law ties it to the virtual fibre."""
        contact, where = self.contact, self.source or "scene"
        # the table rebuilds the contact only while the scene still has the one it gave
        # (a contact replaced in code is kept, or refused below if it has a law)
        from_table = (self.contact_table is not None and contact == _contact(
            self.contact_table, self.fabric, self.discretisation, where))
        if from_table:
            contact = _contact(self.contact_table, fabric, disc, where)
        elif changed and (contact.within_family_law is not None
                          or contact.within_family_stiffness_pa is not None):
            raise InputError(f"Scene.{caller}: this scene's contact was not built from "
                             f"its [contact] table (built or replaced in Python) and depends "
                             f"on the fibre through a compaction law; build it again for "
                             f"{what}")
        return dataclasses.replace(self, fabric=fabric, discretisation=disc, contact=contact)

    def to_dict(self) -> dict:
        """JSON-able resolved scene (SI numbers), protocol sections as given."""
        from .protocols.common import scene_dict

        return {"title": self.title, "source": self.source,
                "fabric": scene_dict(self.fabric),
                "discretisation": scene_dict(self.discretisation),
                "contact": scene_dict(self.contact),
                "materials": {k: scene_dict(v) for k, v in self.materials.items()},
                "protocols": self.protocols}


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file.

    Raises:
        InputError: one line naming the file, the section and the key or value.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(f"cannot read scene file {path}: {exc.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not valid TOML: {exc}") from None
    return parse_scene(data, source=str(path))


def _section(data: dict, name: str, where: str) -> dict:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise InputError(f"{where}: [{name}] must be a table, got {value!r}")
    return value


def _check_keys(table: dict, allowed, where: str, section: str) -> None:
    try:
        schema.check_keys(table, allowed, section)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def _build(where: str, section: str, factory, **kwargs):
    """``factory(**kwargs)`` (an architecture constructor), its errors in scene-file terms."""
    try:
        return factory(**kwargs)
    except InputError as exc:
        raise InputError(f"{where}: [{section}] {exc}") from None
    except TypeError as exc:  # a key given with the wrong shape, e.g. a table for a number
        raise InputError(f"{where}: [{section}] {exc}") from None


def _thickness(value, where: str) -> tuple[float, float | None]:
    """``"1.2 mm at 4.14 kPa"`` -> (thickness [m], pressure [Pa]); a bare length has no pressure."""
    from .units import quantity

    if not isinstance(value, str):
        return quantity(value, "length", "fabric.thickness"), None
    text, _, pressure = value.partition(" at ")
    try:
        t = quantity(text.strip(), "length", "fabric.thickness")
        p = quantity(pressure.strip(), "pressure", "fabric.thickness pressure") \
            if pressure else None
    except InputError as exc:
        raise InputError(f"{where}: [fabric] thickness must read like \"1.2 mm at 4.14 kPa\": "
                         f"{exc}") from None
    return t, p


def _yarn_spec(where: str, section: str, table: dict, materials: dict) -> YarnSpec:
    """A :class:`YarnSpec` from a ``[yarns.<family>]`` table (or an override merged
    into it); ``material`` names a material."""
    kwargs = dict(table)
    mat = kwargs.pop("material", None)
    if mat is None:
        raise InputError(f"{where}: [{section}] needs material = \"<name>\" (one of "
                         f"{', '.join(materials)}, or add a [materials.<name>] table)")
    if mat not in materials:
        raise InputError(f"{where}: [{section}] material {mat!r} is not defined (known: "
                         f"{', '.join(materials)}; add a [materials.{mat}] table)")
    for required in ("linear_density_tex",):
        if required not in kwargs:
            raise InputError(f"{where}: [{section}] needs {required}")
    return schema.build(YarnSpec, kwargs, section, where=where,
                        defaults={"material": materials[mat]})


def _fields(cls) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls))


#: keys of ``[contact] compaction = {...}``
COMPACTION_KEYS = ("law", "coefficient", "modulus_pa", "vf0", "exponent",
                   "reference_pressure_pa", "family")
#: ``[contact] within_family = { form = ... }``: "secant" (linear, matched at the reference
#: pressure) or "law" (the compaction law itself, ContactModel "Within-family law")
WITHIN_FAMILY_FORMS = ("secant", "law")


def _stiffness_from_law(where: str, table, fabric: Fabric, disc: Discretisation,
                        contact_table: dict, section: str = "contact.compaction") -> float:
    """k' [Pa] of ``[contact] compaction = {law = "glass" | "carbon" | "custom", ...}``: the
    line-contact stiffness with which a hexagonal bundle of the family's virtual fibres
    reaches the law's fibre volume fraction at ``reference_pressure_pa`` (default 100 kPa;
    :func:`fabmd.model.compaction.contact_for_yarn`)."""
    from .model.compaction import contact_for_yarn

    if not isinstance(table, dict):
        raise InputError(f"{where}: [{section}] must be a table, got {table!r}")
    _check_keys(table, COMPACTION_KEYS, where, section)
    if section == "contact.compaction" and "normal_stiffness_pa" in contact_table:
        raise InputError(f"{where}: [contact] give normal_stiffness_pa or compaction, not "
                         f"both (the law sets the stiffness)")
    law, fibre, p_ref = _law_and_fibre(where, table, fabric, disc, section)
    try:
        return contact_for_yarn(law, fibre.area_m2, fibre.diameter_m,
                                p_ref)["normal_stiffness_pa"]
    except InputError as exc:
        raise InputError(f"{where}: [{section}] {exc}") from None


def _law_and_fibre(where: str, table: dict, fabric: Fabric, disc: Discretisation,
                   section: str):
    """The compaction law of a ``{law = ..., ...}`` table, the virtual fibre of its
    ``family`` (default warp) and its ``reference_pressure_pa`` (default 100 kPa)."""
    from .model.compaction import CARBON_BUNDLE, GLASS_BUNDLE, CompactionLaw
    from .model.fabric_model import family_beads

    kwargs = dict(table)
    law_name = kwargs.pop("law", "custom")
    family = kwargs.pop("family", "warp")
    p_ref = kwargs.pop("reference_pressure_pa", 1e5)
    laws = {"glass": GLASS_BUNDLE, "carbon": CARBON_BUNDLE}
    if law_name in laws:
        if kwargs:
            raise InputError(f"{where}: [{section}] law = {law_name!r} takes no "
                             f"{', '.join(kwargs)} (use law = \"custom\")")
        law = laws[law_name]
    elif law_name == "custom":
        law = schema.build(CompactionLaw, kwargs, section, where=where)
    else:
        raise InputError(f"{where}: [{section}] law must be one of glass, carbon, custom, "
                         f"got {law_name!r}")
    fams = family_beads(fabric, disc)
    if family not in fams:
        raise InputError(f"{where}: [{section}] family must be one of {', '.join(fams)}, "
                         f"got {family!r}")
    return law, fams[family].fibre, p_ref


def _within_family_law(where: str, table, fabric: Fabric, disc: Discretisation):
    """The :class:`~fabmd.model.bundle_contact.BundleContact` of ``[contact] within_family =
    { law = ..., form = "law" }`` (same-family pairs follow the law itself): that of its
    ``family``, and (family, BundleContact) of every family (the law on its own fibre)."""
    from .model.bundle_contact import BundleContact
    from .model.fabric_model import family_beads

    section = "contact.within_family"
    if "reference_pressure_pa" in table:
        raise InputError(f"{where}: [{section}] reference_pressure_pa applies to form = "
                         f"\"secant\" only (form = \"law\" follows the law at every "
                         f"pressure), got {table['reference_pressure_pa']!r}")
    _check_keys(table, COMPACTION_KEYS, where, section)
    law, fibre, _ = _law_and_fibre(where, table, fabric, disc, section)
    own = {}
    for name, fam in family_beads(fabric, disc).items():
        try:
            own[name] = BundleContact(law, fam.fibre.area_m2, fam.fibre.diameter_m)
        except InputError as exc:
            raise InputError(f"{where}: [{section}] {name}: {exc}") from None
    return BundleContact(law, fibre.area_m2, fibre.diameter_m), tuple(own.items())


def parse_scene(data: dict, source: str = "scene") -> Scene:
    """Validate a scene given as a dict (e.g. parsed TOML); see the module docstring."""
    where = source
    for key, value in data.items():
        if key in OWNED or isinstance(value, dict):  # an owned or a protocol table
            continue
        if key not in TOP_LEVEL_KEYS:
            raise InputError(f"{where}: unknown top-level key {key!r} (allowed: "
                             f"{', '.join(TOP_LEVEL_KEYS)}, or tables "
                             f"{', '.join('[' + s + ']' for s in OWNED)} and protocol tables)")
    protocols = {k: v for k, v in data.items() if k not in OWNED and isinstance(v, dict)}
    materials = _materials(data, where)
    fab = dict(_section(data, "fabric", where))
    specs, overrides = _yarns(data, fab, materials, where)
    fabric = _fabric(fab, specs, overrides, where)
    disc = schema.build(Discretisation, _section(data, "discretisation", where),
                        "discretisation", where=where)
    contact = _contact(_section(data, "contact", where), fabric, disc, where)
    title = data.get("title", "")
    if not isinstance(title, str):
        raise InputError(f"{where}: title must be text, got {title!r}")
    return Scene(fabric=fabric, discretisation=disc, contact=contact, materials=materials,
                 protocols=protocols, title=title, source=source,
                 contact_table=dict(_section(data, "contact", where)))


def _materials(data: dict, where: str) -> dict:
    """The built-in materials and those of ``[materials.NAME]``."""
    materials = dict(BUILTIN_MATERIALS)
    for name, table in _section(data, "materials", where).items():
        if not isinstance(table, dict):
            raise InputError(f"{where}: [materials.{name}] must be a table")
        materials[name] = schema.build(FibreMaterial, table, f"materials.{name}", where=where,
                                       defaults={"name": name},
                                       keys=("modulus_pa", "density_kg_m3"))
    return materials


def _yarn_tables(data: dict, fab: dict, where: str) -> dict:
    """``[yarns.*]`` with ``[fabric] ends_per_m``/``picks_per_m`` moved into their counts."""
    yarn_tables = dict(_section(data, "yarns", where))
    for key, fam in (("ends_per_m", "warp"), ("picks_per_m", "weft")):
        if key not in fab:
            continue
        table = yarn_tables.get(fam)
        if not isinstance(table, dict):
            raise InputError(f"{where}: [fabric] {key} is given but [yarns.{fam}] is missing")
        if "count_per_m" in table or "spacing_m" in table:
            raise InputError(f"{where}: [fabric] {key} and [yarns.{fam}] count_per_m/spacing_m "
                             f"both set the {fam} count; give one")
        yarn_tables[fam] = dict(table, count_per_m=fab.pop(key))
    return yarn_tables


def _yarns(data: dict, fab: dict, materials: dict, where: str) -> tuple[dict, list]:
    """Yarn specs by family and the overrides of ``[[yarns.<family>.overrides]]``."""
    specs, overrides, used = {}, [], set()
    for fam, table in _yarn_tables(data, fab, where).items():
        if fam not in YARN_FAMILIES:
            raise InputError(f"{where}: [yarns.{fam}] is not a yarn family "
                             f"(allowed: {', '.join(YARN_FAMILIES)})")
        if not isinstance(table, dict):
            raise InputError(f"{where}: [yarns.{fam}] must be a table")
        table = dict(table)
        over_tables = table.pop("overrides", [])
        _check_keys(table, _fields(YarnSpec), where, f"yarns.{fam}")
        used.add(table.get("material"))
        specs[fam] = _yarn_spec(where, f"yarns.{fam}", table, materials)
        if not isinstance(over_tables, list) or not all(isinstance(t, dict)
                                                        for t in over_tables):
            raise InputError(f"{where}: [yarns.{fam}] overrides must be a list of tables "
                             f"([[yarns.{fam}.overrides]]), got {over_tables!r}")
        for k, over in enumerate(over_tables, start=1):
            section = f"yarns.{fam}.overrides[{k}]"
            over = dict(over)
            choose = {key: over.pop(key) for key in ("yarns", "layers") if key in over}
            _check_keys(over, _fields(YarnSpec), where, section)
            merged = dict(table, **over)
            if "fibre_volume_fraction" in over and "height_m" not in over:
                merged.pop("height_m", None)  # the override's packing sets its height
            used.add(merged.get("material"))
            spec = _yarn_spec(where, section, merged, materials)
            overrides.append(schema.build(YarnOverride, choose, section, where=where,
                                          defaults={"family": fam, "spec": spec}))
    for name in _section(data, "materials", where):
        if name not in used:  # a misspelt table: the yarn would take a built-in instead
            raise InputError(f"{where}: [materials.{name}] is not used by any yarn (they use "
                             f"{', '.join(sorted(str(u) for u in used))}); check the spelling "
                             f"of the table or of the yarns' material")
    for fam in ("warp", "weft"):
        if fam not in specs:
            raise InputError(f"{where}: [yarns.{fam}] is missing")
    return specs, overrides


def _fabric(fab: dict, specs: dict, overrides: list, where: str) -> Fabric:
    """The :class:`Fabric` of ``[fabric]`` (its architecture keys, datasheet, tiling)."""
    if "thickness" in fab:  # "1.2 mm at 4.14 kPa"
        if "thickness_m" in fab or "thickness_pressure_pa" in fab:
            raise InputError(f"{where}: [fabric] give thickness = \"<t> at <p>\" or "
                             f"thickness_m (+ thickness_pressure_pa), not both")
        fab["thickness_m"], fab["thickness_pressure_pa"] = _thickness(fab.pop("thickness"),
                                                                      where)
    kind = fab.pop("architecture", None)
    if kind not in ARCHITECTURES:
        raise InputError(f"{where}: [fabric] architecture must be one of "
                         f"{', '.join(ARCHITECTURES)}, got {kind!r}")
    factory, arch_keys = ARCHITECTURES[kind]
    _check_keys(fab, tuple(FABRIC_KEYS[1:]) + DATASHEET_KEYS + arch_keys, where, "fabric")
    arch = _build(where, "fabric", factory, **{k: fab.pop(k) for k in arch_keys if k in fab})
    if isinstance(arch, Architecture3D) and "binder" not in specs:
        raise InputError(f"{where}: [yarns.binder] is required: the 3D architecture has "
                         f"{arch.n_binders} binder yarns")
    return schema.build(Fabric, fab, "fabric", where=where, defaults=dict(
        architecture=arch, warp=specs["warp"], weft=specs["weft"], binder=specs.get("binder"),
        overrides=tuple(overrides)))


def _contact(table: dict, fabric: Fabric, disc: Discretisation, where: str) -> ContactModel:
    """``[contact]``, its normal stiffness from ``compaction = {...}`` when given."""
    contact_table = dict(table)
    law_table = contact_table.pop("compaction", None)
    # same-family pairs only (ContactModel "Split contact"): the yarn's compaction law
    within_table = contact_table.pop("within_family", None)
    _check_keys(contact_table, _fields(ContactModel), where, "contact")
    if law_table is not None:
        contact_table["normal_stiffness_pa"] = _stiffness_from_law(
            where, law_table, fabric, disc, contact_table)
    if within_table is not None:
        if "within_family_stiffness_pa" in contact_table:
            raise InputError(f"{where}: [contact] give within_family_stiffness_pa or "
                             "within_family, not both (the law sets the stiffness)")
        if not isinstance(within_table, dict):
            raise InputError(f"{where}: [contact.within_family] must be a table, got "
                             f"{within_table!r}")
        within_table = dict(within_table)
        form = within_table.pop("form", "secant")
        if form not in WITHIN_FAMILY_FORMS:
            raise InputError(f"{where}: [contact.within_family] form must be one of "
                             f"{', '.join(WITHIN_FAMILY_FORMS)}, got {form!r}")
        if form == "law":
            contact_table["within_family_law"], contact_table["within_family_laws"] = \
                _within_family_law(where, within_table, fabric, disc)
        else:
            contact_table["within_family_stiffness_pa"] = _stiffness_from_law(
                where, within_table, fabric, disc, contact_table, "contact.within_family")
    return schema.build(ContactModel, contact_table, "contact", where=where)
