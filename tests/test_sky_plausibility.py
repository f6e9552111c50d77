"""Bad photos refused (natscene.sky.plausibility, natscene.io decoding checks), calibrated on the bundled
photos: the kite photo and realistic variants of it pass; the flower photo as a cloud photo, a garden, a dark
overcast sky, a cloud close-up without sky, colour casts, negative linear values and truncated files are
refused with the photo's name, what was found and what to do, unless accept_unusual."""
from pathlib import Path

import cv2
import numpy as np
import pytest

from natscene import io
from natscene.config import default_settings, settings_from_section
from natscene.errors import InputError
from natscene.sky.extract import SkySettings, extract_sky
from natscene.sky.plausibility import PlausibilityLimits, findings, measure

ROOT = Path(__file__).resolve().parents[1]
KITE = ROOT / "resources" / "photos" / "kite_cumulus_left.jpg"
FLOWER = ROOT / "resources" / "photos" / "freshflower.jpg"
GRASS = ROOT / "resources" / "textures" / "grass_meadow_256.png"


@pytest.fixture(scope="module")
def kite():
    return io.read_photo(KITE)


def garden() -> np.ndarray:
    """A lawn (the bundled grass, slightly defocused) with a red-orange flower (the bundled flower) in it."""
    g = cv2.GaussianBlur(np.tile(io.read_photo(GRASS), (2, 3, 1))[:480, :640], (0, 0), 1.5)
    fl = cv2.resize(io.read_photo(FLOWER)[100:400, 150:450], (200, 200), interpolation=cv2.INTER_AREA)
    yy, xx = np.mgrid[:200, :200]
    disc = (((yy - 100) ** 2 + (xx - 100) ** 2) < 95 ** 2)[..., None]
    g[140:340, 220:420] = np.where(disc, fl, g[140:340, 220:420])
    return g


def dark_overcast(kite) -> np.ndarray:
    """The kite photo as a dark, colourless overcast sky (grey clouds on a grey sky)."""
    y = kite @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    return (np.clip(y[..., None] * 0.3 + 0.01, 0, 1) * np.array([0.96, 1.0, 1.06], np.float32)).astype(np.float32)


def _extract(photo, **kw):
    return extract_sky(photo, default_settings(SkySettings, **kw), name="test.jpg (photos.test)", key="photos.test")


GOOD = {
    "kite": lambda k: k,
    "left half": lambda k: np.ascontiguousarray(k[:, :320]),
    "underexposed x0.4": lambda k: k * 0.4,
    "overexposed x1.8": lambda k: np.clip(k * 1.8, 0, 1),
    "warm white balance": lambda k: np.clip(k * np.array([1.0, 0.8, 0.55], np.float32), 0, 1),
    "cool white balance": lambda k: np.clip(k * np.array([0.85, 0.95, 1.0], np.float32), 0, 1),
}


@pytest.mark.parametrize("variant", list(GOOD), ids=list(GOOD))
def test_cloud_photos_pass(kite, variant):
    res = _extract(GOOD[variant](kite))
    assert res.warnings == [] or all("unusual" not in w for w in res.warnings)
    m = res.plausibility
    assert m["cloud_to_sky_saturation"] < 0.3 and 4500 < m["sun_cct_k"] < 8000 and abs(m["sun_duv"]) < 0.01


BAD = {
    "flower": (lambda k: io.read_photo(FLOWER), ["not cloud-coloured", "not sky-coloured", "far from daylight"]),
    "garden": (lambda k: garden(), ["not cloud-coloured", "not sky-coloured", "far from daylight"]),
    "dark overcast": (dark_overcast, ["grey"]),
    "cloud close-up": (lambda k: cv2.resize(np.ascontiguousarray(k[220:400, 0:60]), (240, 720),
                                            interpolation=cv2.INTER_CUBIC), ["too little sky"]),
    "green cast": (lambda k: np.clip(k * np.array([0.6, 1.0, 0.6], np.float32), 0, 1), ["far from daylight"]),
    "magenta cast": (lambda k: np.clip(k * np.array([1.0, 0.6, 1.0], np.float32), 0, 1), ["far from daylight"]),
    "blue sky only": (lambda k: np.ascontiguousarray(k[200:, 330:]), ["not cloud-coloured"]),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_implausible_photos_are_refused(kite, case):
    make, words = BAD[case]
    with pytest.raises(InputError) as e:
        _extract(make(kite))
    msg = str(e.value)
    assert msg.startswith("test.jpg (photos.test)")
    for w in words:
        assert w in msg, msg
    assert "photos.test.mask" in msg and "another photo" in msg and "photos.test.accept_unusual: true" in msg


def test_flower_photo_as_in_the_issue(kite):
    """The issue's case: freshflower.jpg as a cloud photo gave c_in [2.99, 0.51, 0.01] and no warning."""
    m = None
    with pytest.raises(InputError, match="1667 K"):
        _extract(io.read_photo(FLOWER))
    res = _extract(io.read_photo(FLOWER), accept_unusual=True)
    m = res.plausibility
    assert m["sun_cct_k"] < 2000 and np.allclose(res.sun.c_in, [2.99, 0.51, 0.01], atol=0.02)
    unusual = [w for w in res.warnings if "photos.test.accept_unusual" in w]
    assert len(unusual) == 3
    summary = res.summary()
    assert summary["warnings"] == res.warnings and summary["plausibility"]["sun_cct_k"] < 2000


def test_too_little_cloud_with_a_strict_threshold(kite):
    with pytest.raises(InputError, match="too little cloud"):
        _extract(kite, threshold=0.01)


def test_negative_linear_values(kite):
    exr = kite - 0.05
    with pytest.raises(InputError, match=r"negative linear values.*photos.test.accept_unusual"):
        _extract(exr)
    res = _extract(np.where(kite > 0.02, kite, kite - 0.001), accept_unusual=True)
    assert any("negative" in w for w in res.warnings)
    assert float(res.photo.min()) >= 0.0


def test_non_finite_values_are_always_refused(kite):
    bad = kite.copy()
    bad[10, 10, 1] = np.nan
    for accept in (False, True):
        with pytest.raises(InputError, match="NaN"):
            _extract(bad, accept_unusual=accept)


def test_limits_are_configurable(kite):
    m = measure(kite, _extract(kite).labels, _extract(kite).sun.c_in)
    assert findings(m, default_settings(PlausibilityLimits)) == []
    assert findings(m, default_settings(PlausibilityLimits, min_sky_fraction=0.9))  # the kite photo has 84 % sky
    assert settings_from_section(PlausibilityLimits, {"sun_cct_k": [1000, 3000]}, "sky.checks").sun_cct_k == (1000, 3000)


# --------------------------------------------------------------------------------------- damaged files
def _jpeg_bytes(img: np.ndarray, path: Path) -> bytes:
    io.write_png(path.with_suffix(".png"), img, exposure=1.0)
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(str(path.with_suffix(".png")))
    assert buf.write(str(path))
    return path.read_bytes()


@pytest.mark.parametrize("keep", [2048, 0.6, 0.98])
def test_truncated_jpeg_is_refused_with_its_name(tmp_path, keep):
    data = KITE.read_bytes()
    n = keep if isinstance(keep, int) else int(len(data) * keep)
    bad = tmp_path / "cut.jpg"
    bad.write_bytes(data[:n])
    with pytest.raises(InputError, match=r"cut\.jpg.*truncated JPEG"):
        io.read_photo(bad)


def test_truncation_is_found_behind_an_exif_thumbnail(tmp_path, kite):
    """A thumbnail inside APP1 carries its own start-of-scan and end-of-image markers; they must not count."""
    thumb = _jpeg_bytes(cv2.resize(kite, (32, 24), interpolation=cv2.INTER_AREA), tmp_path / "t.jpg")
    main = KITE.read_bytes()
    app1 = b"Exif\x00\x00" + thumb
    data = main[:2] + b"\xff\xe1" + (len(app1) + 2).to_bytes(2, "big") + app1 + main[2:]
    whole = tmp_path / "whole.jpg"
    whole.write_bytes(data)
    assert io.read_photo(whole).shape == kite.shape  # a valid file with a thumbnail reads fine
    cut = tmp_path / "cut.jpg"
    cut.write_bytes(data[:len(data) // 2])
    with pytest.raises(InputError, match="truncated JPEG"):
        io.read_photo(cut)


def test_truncated_png_and_decoder_errors(tmp_path):
    data = GRASS.read_bytes()
    cut = tmp_path / "cut.png"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\.png.*truncated PNG"):
        io.read_photo(cut)
    # a PNG whose IEND survives but whose image data is damaged: the decoder's error names the file
    broken = bytearray(data)
    i = data.find(b"IDAT") + 40
    broken[i:i + 200] = bytes(200)
    bad = tmp_path / "broken.png"
    bad.write_bytes(bytes(broken))
    with pytest.raises(InputError, match=r"broken\.png"):
        io.read_photo(bad)


def test_exr_headers_carry_no_wall_clock_time(tmp_path):
    a = np.ones((4, 4, 3), np.float32)
    io.write_exr(tmp_path / "a.exr", a)
    io.write_exr(tmp_path / "b.exr", a)
    assert b"capDate" not in (tmp_path / "a.exr").read_bytes()
    assert "DateTime" not in io.read_exr(tmp_path / "a.exr").attrs
    assert (tmp_path / "a.exr").read_bytes() == (tmp_path / "b.exr").read_bytes()


def test_stale_temp_files_are_removed(tmp_path):
    target = tmp_path / "sky.exr"
    stale = [tmp_path / ".sky.ab12cd_9.exr", tmp_path / ".sky.zzzzzzzz.exr"]
    keep = [tmp_path / ".sky.ab12cd_9.png", tmp_path / ".skyline.abcdefgh.exr", tmp_path / "sky.exr.bak"]
    for f in stale + keep:
        f.write_bytes(b"x")
    removed = io.remove_stale_temps(target)
    assert sorted(removed) == sorted(stale)
    assert all(f.exists() for f in keep)
