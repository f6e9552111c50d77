"""Settings from config sections (natscene.config.settings_from_section): the schema holds the defaults, the only
ones: a settings dataclass's configurable fields have no default of their own (``SCHEMA`` names the schema sections
they come from), so a library call without a config behaves as the workflow with an empty config section."""
import dataclasses

import pytest

from natscene.config import (complete_section, default_settings, schema_defaults, schema_section,
                             settings_from_section)
from natscene.errors import ConfigError
from natscene.features.optimisation import OptimisationSettings
from natscene.features.quilting import QuiltingSettings
from natscene.fit.genetic import DEFAULT_RANGES
from natscene.fit.settings import FitSettings, GradientSettings, KappaGridSettings, fit_settings
from natscene.leaves.season import SeasonParams
from natscene.mie.march import MieRender, mie_render
from natscene.scatter.allorders import AllOrdersSettings, frame_settings, settings_from_config
from natscene.sky.daylight import Skylight, skylight
from natscene.sky.extract import SkySettings
from natscene.sky.plausibility import PlausibilityLimits
from natscene.tiles.tile_ga import GAParams

# (dataclass, keys of its first schema section that are not fields of it: they configure something else)
CLASSES = [
    (SkySettings, {"fit_resolutions"}),
    (PlausibilityLimits, set()),
    (GAParams, set()),
    (SeasonParams, set()),
    (AllOrdersSettings, set()),
    (FitSettings, set()),
    (KappaGridSettings, set()),
    (GradientSettings, set()),
    (OptimisationSettings, set()),
    (QuiltingSettings, set()),
    (Skylight, set()),
    (MieRender, set()),
]
# patterns.*.rd (RDParams) and volumes.* (natscene.volume.procedural.Shape) have no per-key schema defaults on
# purpose: their defaults depend on a preset / the cloud kind (Dong's Table 3.3 rows, the kinds' shapes), and an
# absent key means "the preset's value"; the schemas' descriptions name the presets.


def _own_default(f: dataclasses.Field) -> bool:
    return f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING


@pytest.mark.parametrize("cls, not_fields", CLASSES, ids=[c[0].__name__ for c in CLASSES])
def test_the_schema_holds_the_only_defaults(cls, not_fields):
    """Every key of the class's own section is a field; a field is configurable (a key with a schema default, in
    one of the sections ``cls.SCHEMA`` names) or has a default of its own, never both; the default instance is
    the schema's."""
    renames = getattr(cls, "CONFIG_NAMES", {})
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    file, path = cls.SCHEMA[0]
    keys = {renames.get(k, k) for k in schema_section(file, path)["properties"] if k not in not_fields}
    assert keys <= set(fields), sorted(keys - set(fields))
    configurable = {renames.get(k, k) for k in schema_defaults(cls)}
    for name, f in fields.items():
        assert (name in configurable) != _own_default(f), (
            f"{cls.__name__}.{name}: " + ("a default of its own and the schema's" if _own_default(f)
                                          else "neither a schema default nor one of its own"))
    d = default_settings(cls)
    for k, v in schema_defaults(cls).items():
        got = getattr(d, renames.get(k, k))
        assert got == (tuple(v) if isinstance(got, tuple) else v), f"{cls.__name__}.{k}"


def test_settings_from_section_names_unknown_keys_and_converts():
    with pytest.raises(ConfigError, match=r"'tiles\.grass\.ga\.pop': unknown setting; allowed: .*lambda"):
        settings_from_section(GAParams, {"pop": 3}, "tiles.grass.ga")
    p = settings_from_section(GAParams, {"lambda": 0.5, "pop_size": 12}, "tiles.grass.ga")
    assert (p.lam, p.pop_size, p.n_g) == (0.5, 12, default_settings(GAParams).n_g)
    lim = settings_from_section(PlausibilityLimits, {"sun_cct_k": [1000, 3000]}, "sky.checks")
    assert lim.sun_cct_k == (1000, 3000) and isinstance(lim.sun_cct_k, tuple)
    assert settings_from_section(SkySettings, None, "sky") == default_settings(SkySettings)
    # a key the section lacks takes the schema's default
    assert settings_from_section(PlausibilityLimits, {"max_sun_duv": 0.5}, "sky.checks") == \
        default_settings(PlausibilityLimits, max_sun_duv=0.5)


def test_fit_settings_read_nested_sections_and_ranges_default_to_the_schema():
    """fit.kappa and fit.gradient become their dataclasses, epsilon_O its field, unknown keys name their path;
    the GA's default ranges (natscene.fit.genetic.DEFAULT_RANGES) are the schema's defaults of fit.ranges."""
    st = fit_settings({"epsilon_O": 0.3, "kappa": {"max": 0.5}, "gradient": {"h": 0.02}})
    assert (st.epsilon_o, st.kappa, st.gradient.h, st.gradient.n_alpha) == \
        (0.3, default_settings(KappaGridSettings, max=0.5), 0.02, 10)
    default = fit_settings(None)
    assert (default.kappa, default.gradient) == (default_settings(KappaGridSettings), default_settings(GradientSettings))
    assert default == fit_settings(complete_section({}, "fit.schema.yaml", (), "fit"))
    with pytest.raises(ConfigError, match=r"'fit\.kappa\.top'"):
        fit_settings({"kappa": {"top": 1.0}})
    with pytest.raises(ConfigError, match=r"'fit\.pop'"):
        fit_settings({"pop": 3})
    ranges = schema_section("fit.schema.yaml", ["ranges"])["properties"]
    assert {k: tuple(v["default"]) for k, v in ranges.items()} == DEFAULT_RANGES
    assert {k: tuple(v) for k, v in default.ranges.items()} == DEFAULT_RANGES


def test_the_sky_blocks_agree():
    """precompute.skylight declares model and turbidity as the shots' sky does (the same defaults), and completed
    (natscene.sky.daylight.skylight) it is the shots' default sky: the precompute's dome and the frames' agree."""
    pre = schema_section("precompute.schema.yaml", ("skylight",))["properties"]
    shot = schema_section("shots.schema.yaml", ("additionalProperties", "sky"))["properties"]
    assert set(pre) <= set(shot)
    assert {k: v["default"] for k, v in pre.items()} == {k: shot[k]["default"] for k in pre}
    assert set(pre["model"]["enum"]) <= set(shot["model"]["enum"])
    validated = complete_section({}, "precompute.schema.yaml", ("skylight",), "precompute.skylight")
    assert skylight(validated, "precompute.skylight") == skylight(None) == default_settings(Skylight)
    assert skylight({"turbidity": 5, "color": [1, 2, 3]}).color == (1, 2, 3)


def test_each_config_concept_is_completed_in_one_place():
    """The all-orders settings of a precompute section and of a shot's frames (the shot's budgets, tally rate,
    ground share as p_ground, march; the camera lobe off; photon caps that follow the budgets), the Mie render's:
    each from the schema's defaults, whatever part of the section is given."""
    pre = complete_section({}, "precompute.schema.yaml", (), "precompute")
    assert settings_from_config(pre) == settings_from_config({}) == default_settings(AllOrdersSettings)
    st = frame_settings({"sun_collisions": 40_000_000, "ground_share": 0.3, "step_voxels": 0.25})
    shots = complete_section({}, "shots.schema.yaml", ("additionalProperties", "render"), "shots.<name>.render")
    assert (st.sun_collisions, st.sky_collisions, st.tally_rate, st.p_ground, st.step_voxels, st.camera_lobe) == \
        (40_000_000, shots["sky_collisions"], shots["tally_rate"], 0.3, 0.25, 0.0)
    assert (st.sun_photons_max, st.sky_photons_max) == (20_000_000, shots["sky_collisions"] // 2)
    assert (st.fine_voxels, st.noise_target) == (pre["all_orders"]["fine_voxels"], (0.0, 0.0))
    with pytest.raises(ConfigError, match="shots.<name>.render"):
        frame_settings({"ground_share": 2.0})
    r = mie_render({"L_in": 3.0})
    assert (r.L_in, r.mie_scale, r.c_in) == (3.0, 1.0, tuple(schema_section("mie.schema.yaml", ("render",))[
        "properties"]["c_in"]["default"]))
    assert mie_render(r) is r
