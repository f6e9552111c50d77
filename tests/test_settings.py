"""Settings from config sections (natscene.config.settings_from_section): the schema holds the defaults, and every
settings dataclass's defaults equal its schema's, so a library call without a config behaves as the workflow
with an empty config section."""
import dataclasses
from pathlib import Path

import pytest

from natscene.config import bundle_schema, settings_from_section
from natscene.errors import ConfigError
from natscene.fit.genetic import DEFAULT_RANGES
from natscene.features.optimisation import OptimisationSettings
from natscene.fit.settings import FitSettings, GradientSettings, KappaGridSettings, fit_settings
from natscene.leaves.season import SeasonParams
from natscene.scatter.allorders import AllOrdersSettings
from natscene.sky.extract import SkySettings
from natscene.sky.plausibility import PlausibilityLimits
from natscene.tiles.tile_ga import GAParams

SCHEMAS = Path(__file__).resolve().parents[1] / "workflow" / "schemas"

# (dataclass, schema file, path to the section's object schema inside it, schema keys that are not fields of the
# dataclass (they configure something else), fields that come from another section: {field: (file, path)},
# fields that are not configurable (no config key; the dataclass's default is the only value))
PAIRS = [
    (SkySettings, "sky.schema.yaml", [], {"fit_resolutions"},
     {"accept_unusual": ("photos.schema.yaml", ["additionalProperties"])}, set()),
    (PlausibilityLimits, "sky.schema.yaml", ["checks"], set(), {}, set()),
    (GAParams, "tiles.schema.yaml", ["additionalProperties", "ga"], set(), {}, set()),
    (SeasonParams, "leaves.schema.yaml", ["season"], set(), {}, set()),
    (AllOrdersSettings, "precompute.schema.yaml", ["all_orders"], set(),
     {"step_voxels": ("precompute.schema.yaml", []), "supersample": ("precompute.schema.yaml", [])},
     {"majorant_voxels", "p_ground", "sun_bands", "sky_bands", "window_voxels", "sky_lobe_g"}),
    (FitSettings, "fit.schema.yaml", [], {"kappa", "gradient"}, {}, {"kappa", "gradient"}),
    (KappaGridSettings, "fit.schema.yaml", ["kappa"], set(), {}, set()),
    (GradientSettings, "fit.schema.yaml", ["gradient"], set(), {}, set()),
    (OptimisationSettings, "textures.schema.yaml", ["additionalProperties", "optimisation"], set(), {},
     {"type_mode"}),  # type_mode is textures.<name>.types.mode, set by natscene.features.entry
]
# patterns.*.rd (RDParams) and volumes.* (natscene.volume.procedural.Shape) have no per-key schema defaults on
# purpose: their defaults depend on a preset / the cloud kind (Dong's Table 3.3 rows, the kinds' shapes), and an
# absent key means "the preset's value"; the schemas' descriptions name the presets.


def _section(file: str, path: list) -> dict:
    node = bundle_schema(SCHEMAS / file)
    for part in path:
        node = node[part] if part == "additionalProperties" else node["properties"][part]
    return node


def _default(f: dataclasses.Field):
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return dataclasses.MISSING


@pytest.mark.parametrize("cls, file, path, not_fields, elsewhere, internal", PAIRS, ids=[p[0].__name__ for p in PAIRS])
def test_dataclass_defaults_equal_schema_defaults(cls, file, path, not_fields, elsewhere, internal):
    schema = _section(file, path)["properties"]
    renames = getattr(cls, "CONFIG_NAMES", {})
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init and f.name not in internal}
    keys = {renames.get(k, k): k for k in schema if k not in not_fields}
    # every config key is a field and every configurable field is a config key (here or in the section it comes from)
    assert set(keys) | set(elsewhere) == set(fields), (sorted(set(keys) ^ set(fields)))
    for name, f in fields.items():
        if name in elsewhere:
            other_file, other_path = elsewhere[name]
            sub = _section(other_file, other_path)["properties"][name]
        else:
            sub = schema[keys[name]]
        assert "default" in sub, f"{file}: '{name}' has no default in the schema"
        expected = settings_from_section(cls, {keys.get(name, name): sub["default"]}, "test")
        assert getattr(expected, name) == _default(f), (
            f"{cls.__name__}.{name}: dataclass default {_default(f)!r} != schema default {sub['default']!r}")


def test_settings_from_section_names_unknown_keys_and_converts():
    with pytest.raises(ConfigError, match=r"'tiles\.grass\.ga\.pop': unknown setting; allowed: .*lambda"):
        settings_from_section(GAParams, {"pop": 3}, "tiles.grass.ga")
    p = settings_from_section(GAParams, {"lambda": 0.5, "pop_size": 12}, "tiles.grass.ga")
    assert (p.lam, p.pop_size, p.n_g) == (0.5, 12, GAParams().n_g)
    lim = settings_from_section(PlausibilityLimits, {"sun_cct_k": [1000, 3000]}, "sky.checks")
    assert lim.sun_cct_k == (1000, 3000) and isinstance(lim.sun_cct_k, tuple)
    assert settings_from_section(SkySettings, None, "sky") == SkySettings()


def test_fit_settings_read_nested_sections_and_ranges_default_to_the_schema():
    """fit.kappa and fit.gradient become their dataclasses, epsilon_O its field, unknown keys name their path;
    the GA's default ranges (natscene.fit.genetic.DEFAULT_RANGES) are the schema's defaults of fit.ranges."""
    st = fit_settings({"epsilon_O": 0.3, "kappa": {"max": 0.5}, "gradient": {"h": 0.02}})
    assert (st.epsilon_o, st.kappa, st.gradient.h, st.gradient.n_alpha) == (0.3, KappaGridSettings(max=0.5), 0.02, 10)
    assert fit_settings(None) == FitSettings()
    with pytest.raises(ConfigError, match=r"'fit\.kappa\.top'"):
        fit_settings({"kappa": {"top": 1.0}})
    with pytest.raises(ConfigError, match=r"'fit\.pop'"):
        fit_settings({"pop": 3})
    ranges = _section("fit.schema.yaml", ["ranges"])["properties"]
    assert {k: tuple(v["default"]) for k, v in ranges.items()} == DEFAULT_RANGES
