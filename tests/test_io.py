"""natscene.io: EXR round trips, atomic writes, photo decoding, the documented PNG tone map."""
import numpy as np
import OpenImageIO as oiio
import pytest

from natscene import io
from natscene.errors import InputError


def test_exr_roundtrip_float32_bit_exact_with_attributes(tmp_path):
    rng = np.random.default_rng(0)
    names = ["R", "G", "B", "A", "sun.s0.3", "k2.g0.5.s0.3", "depth"]
    pix = rng.normal(size=(17, 23, len(names))).astype(np.float32) * 1e3
    pix[0, 0, 0] = np.float32(1e-30)  # denormal-ish, must survive
    attrs = {"stage": "test", "sigma_t": 0.3, "orders": [2, 3, 4], "n": 7, "nested": {"a": [1.5, "x"]}}
    path = tmp_path / "a.exr"
    io.write_exr(path, pix, names, attrs=attrs, stage="unit")
    img = io.read_exr(path)
    assert img.channels == names
    assert img.pixels.dtype == np.float32
    assert np.array_equal(img.pixels.view(np.uint32), pix.view(np.uint32))  # bit-exact
    for k, v in attrs.items():
        assert img.attrs[k] == v
    assert img.attrs["stage"] == "unit" or img.attrs["stage"] == "test"
    assert img.attrs["version"] == __import__("natscene").__version__
    np.testing.assert_array_equal(img.channel("sun.s0.3"), pix[..., 4])


def test_exr_of_more_than_1024_channels_reads_back(tmp_path):
    """The all-orders tables of the main job are 1035 channels (OpenImageIO's default limit is 1024)."""
    names = [f"c{i}" for i in range(1500)]
    pix = np.arange(2 * 3 * len(names), dtype=np.float32).reshape(2, 3, len(names))
    io.write_exr(tmp_path / "wide.exr", pix, names, half=True)
    img = io.read_exr(tmp_path / "wide.exr")
    assert img.channels == names
    np.testing.assert_allclose(img.pixels, pix, rtol=1e-3)


def test_exr_half_within_half_precision(tmp_path):
    pix = np.linspace(0.001, 100, 5 * 7 * 3, dtype=np.float32).reshape(5, 7, 3)
    io.write_exr(tmp_path / "h.exr", pix, half=True)
    back = io.read_exr(tmp_path / "h.exr").pixels
    np.testing.assert_allclose(back, pix, rtol=1e-3)
    inp = oiio.ImageInput.open(str(tmp_path / "h.exr"))
    assert inp.spec().format == oiio.TypeDesc("half")
    inp.close()


def test_exception_mid_write_leaves_no_file(tmp_path):
    target = tmp_path / "out.exr"
    with pytest.raises(RuntimeError):
        with io.atomic_path(target) as tmp:
            tmp.write_bytes(b"partial")
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_failing_exr_write_leaves_nothing(tmp_path, monkeypatch):
    class Boom(Exception):
        pass

    def explode(self, *a, **k):
        raise Boom()

    monkeypatch.setattr(oiio.ImageOutput, "write_image", explode)
    with pytest.raises(Boom):
        io.write_exr(tmp_path / "x.exr", np.zeros((4, 4, 3), np.float32))
    assert list(tmp_path.iterdir()) == []


def test_existing_file_untouched_by_failed_write(tmp_path):
    target = tmp_path / "keep.exr"
    io.write_exr(target, np.ones((2, 2, 3), np.float32))
    before = target.read_bytes()
    with pytest.raises(ValueError):
        io.write_exr(target, np.ones((2, 2, 3), np.float32), channels=["R", "G"])
    assert target.read_bytes() == before


def _write_png_u(path, arr, fmt):
    spec = oiio.ImageSpec(arr.shape[1], arr.shape[0], arr.shape[2], fmt)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(arr)
    out.close()


@pytest.mark.parametrize("bits", [8, 16])
def test_read_photo_decodes_srgb(tmp_path, bits):
    # sRGB code 0.5 -> linear 0.21404 (IEC 61966-2-1), code 1 -> 1, code 0 -> 0
    if bits == 8:
        arr = np.array([[[0, 128, 255]]], np.uint8)
        codes = arr / 255.0
        fmt = oiio.UINT8
    else:
        arr = np.array([[[0, 32768, 65535]]], np.uint16)
        codes = arr / 65535.0
        fmt = oiio.UINT16
    _write_png_u(tmp_path / "p.png", arr, fmt)
    lin = io.read_photo(tmp_path / "p.png")
    expected = np.where(codes <= 0.04045, codes / 12.92, ((codes + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(lin[0, 0], expected[0, 0], atol=2e-6)


def test_read_photo_exr_is_linear_and_errors(tmp_path):
    pix = np.full((3, 4, 3), 2.5, np.float32)
    io.write_exr(tmp_path / "p.exr", pix)
    np.testing.assert_array_equal(io.read_photo(tmp_path / "p.exr"), pix)
    with pytest.raises(InputError, match="not found"):
        io.read_photo(tmp_path / "missing.jpg")
    (tmp_path / "junk.jpg").write_bytes(b"not an image")
    with pytest.raises(InputError, match="junk.jpg"):
        io.read_photo(tmp_path / "junk.jpg")


def test_png_tone_map_is_the_documented_one(tmp_path):
    lin = np.array([[[0.0, 0.21404114, 1.0], [2.0, 0.5, 0.25]]], np.float32)
    io.write_png(tmp_path / "t.png", lin, exposure=1.0)
    back = io.read_image_u8(tmp_path / "t.png")
    assert back[0, 0].tolist() == [0, 128, 255]
    assert back[0, 1, 0] == 255  # clipped
    # auto exposure maps the 99.5th percentile of luminance to 1
    assert io.auto_exposure(np.full((4, 4, 3), 0.25, np.float32)) == pytest.approx(4.0)


def test_colour_module_yiq_and_srgb_roundtrip():
    from natscene import color
    rgb = np.random.default_rng(2).uniform(0, 1, (10, 3)).astype(np.float32)
    yiq = color.srgb_to_yiq(rgb)
    np.testing.assert_allclose(yiq[:, 0], rgb @ [0.299, 0.587, 0.114], atol=1e-6)   # Y = Rec. 601 luma
    np.testing.assert_allclose(color.srgb_to_yiq(np.ones(3)), [1, 0, 0], atol=1e-5)  # white has no chroma
    np.testing.assert_allclose(color.yiq_to_srgb(yiq), rgb, atol=1e-5)
    np.testing.assert_allclose(color.linear_to_srgb(color.srgb_to_linear(rgb)), rgb, atol=1e-5)
