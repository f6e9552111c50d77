"""Config validation: defaults filled from the schemas, errors naming the key path."""
import copy
from pathlib import Path

import pytest

from natscene.config import bundle_schema, load_yaml_config, relative_to_root, resolve_path, validate_config
from natscene.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "workflow" / "schemas" / "config.schema.yaml"


@pytest.fixture(scope="module")
def smoke():
    return load_yaml_config(ROOT / "config" / "smoke.yaml")


@pytest.mark.parametrize("name", ["config.yaml", "smoke.yaml"])
def test_bundled_configs_are_valid(name):
    validate_config(load_yaml_config(ROOT / "config" / name), SCHEMA)


def test_gpu_overlay_merges_onto_the_main_job():
    """config/gpu.yaml is an overlay (two --configfile arguments): merged the way Snakemake merges them, the
    main job keeps its sections, its photon budget and its noise target, its nodes may be topped up to 64x (not
    16x), and the result is valid."""
    from snakemake.utils import update_config
    main = load_yaml_config(ROOT / "config" / "config.yaml")
    cfg = copy.deepcopy(main)
    update_config(cfg, load_yaml_config(ROOT / "config" / "gpu.yaml"))
    cfg = validate_config(cfg, SCHEMA)
    ao, main_ao = cfg["precompute"]["all_orders"], main["precompute"]["all_orders"]
    assert cfg["precompute"]["pairs"] == main["precompute"]["pairs"] and cfg["volumes"] == \
        validate_config(copy.deepcopy(main), SCHEMA)["volumes"]
    for key in ("sun_collisions", "sky_collisions", "noise_target"):
        assert ao[key] == main_ao[key], key
    assert main_ao["max_budget_scale"] == 16 and ao["max_budget_scale"] == 64


def test_defaults_are_filled_inside_referenced_sections(smoke):
    cfg = validate_config(copy.deepcopy(smoke), SCHEMA)
    vol = cfg["volumes"]["tiny"]
    assert vol["grid"] == "density" and vol["reference_optical_depth"] == 60.0 and vol["size"] is None
    assert vol["extinction_scale"] is None
    assert cfg["views"]["tiny"]["camera"]["up"] == [0, 1, 0]


def test_schema_bundle_has_no_refs():
    assert "$ref" not in str(bundle_schema(SCHEMA))


@pytest.mark.parametrize("mutate, key, words", [
    (lambda c: c["volumes"]["tiny"].__setitem__("resoltion", [3, 3, 3]), "volumes.tiny", "resoltion"),
    (lambda c: c["volumes"]["tiny"].__setitem__("resolution", [0, 8, 8]), "volumes.tiny.resolution[0]", "minimum"),
    (lambda c: c["volumes"]["tiny"].__setitem__("resolution", [8, 2048, 8]), "volumes.tiny.resolution[1]", "maximum"),
    (lambda c: c["volumes"]["tiny"].__setitem__("kind", "stratus"), "volumes.tiny.kind", "stratus"),
    (lambda c: c.__setitem__("volumns", {}), "(top level)", "volumns"),
    (lambda c: c["views"]["tiny"]["camera"].__setitem__("fov", 200), "views.tiny.camera.fov", "200"),
])
def test_bad_values_name_the_key(smoke, mutate, key, words):
    cfg = copy.deepcopy(smoke)
    mutate(cfg)
    with pytest.raises(ConfigError) as e:
        validate_config(cfg, SCHEMA, source="smoke.yaml")
    msg = str(e.value)
    assert f"'{key}'" in msg and words in msg and "smoke.yaml" in msg


def test_recolour_library_defaults_match_the_schema():
    """natscene.patterns.recolour.DEFAULTS (for library calls) and the schema the workflow fills from agree."""
    from natscene.patterns.recolour import DEFAULTS
    cfg = validate_config({"recolour": {"x": {"photo": "p.jpg"}}}, SCHEMA)
    filled = {k: v for k, v in cfg["recolour"]["x"].items() if k != "photo"}
    assert filled == DEFAULTS


def test_metadata_paths_are_relative_to_the_repository(tmp_path):
    """relative_to_root undoes resolve_path for a path under the repository (what the config wrote, POSIX), and
    keeps any other path absolute: products that record their inputs are the same bytes in every checkout."""
    root = tmp_path / "checkout"
    assert relative_to_root(resolve_path("resources/photos/a.jpg", root), root) == "resources/photos/a.jpg"
    other = tmp_path / "elsewhere" / "b.png"
    assert relative_to_root(other, root) == str(other)
    assert relative_to_root(resolve_path(str(other), root), root) == str(other)


def test_canonical_sorts_keys_and_writes_numbers_as_the_schema_means():
    from natscene.config import canonical
    schema = {"type": "object", "properties": {"a": {"type": "number"}, "n": {"type": "integer"},
                                               "m": {"type": ["number", "null"]},
                                               "v": {"type": "array", "items": {"type": "number"}}},
              "additionalProperties": {"type": "object", "properties": {"x": {"type": "number"}}}}
    got = canonical({"v": (1, 2.5), "n": 3, "m": 2, "a": 3, "zz": {"x": 1, "b": True}}, schema)
    assert got == {"a": 3.0, "m": 2.0, "n": 3, "v": [1.0, 2.5], "zz": {"b": True, "x": 1.0}}
    assert list(got) == ["a", "m", "n", "v", "zz"] and list(got["zz"]) == ["b", "x"]
    assert isinstance(got["n"], int) and isinstance(got["a"], float) and got["zz"]["b"] is True


def test_equivalent_configs_validate_to_the_same_text(smoke):
    """Reordered keys, written-out defaults and 3 for 3.0 give the same validated config, key order included
    (Snakemake compares params by their text)."""
    def rev(node):
        return {k: rev(node[k]) for k in reversed(list(node))} if isinstance(node, dict) else node
    raw = load_yaml_config(ROOT / "config" / "smoke.yaml")
    other = rev(copy.deepcopy(raw))
    other["precompute"]["skylight"] = {"turbidity": 3, "model": "preetham"}
    other["fit"]["population"] = 20
    a = validate_config(copy.deepcopy(raw), SCHEMA)
    b = validate_config(other, SCHEMA)
    assert repr(a) == repr(b)
