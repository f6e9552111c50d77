"""The README's and the docs' images of the main job, made from its results (after ``make run``).

    .venv/bin/python tools/doc_images.py [--results results]

Writes into docs/img/:

- ``composite_day_to_sunset.jpg``: the ``day_to_sunset`` composite, frames 0 and 23
  (``composite/day_to_sunset/<frame>/final.png``) side by side, 8 white pixels apart;
- ``composite_detail.png``: two crops of frame 0 (rows 250-480, columns 0-330: the beetles and leaves; rows 170-400,
  columns 310-640: the flowers) side by side, enlarged twice (nearest neighbour);
- ``composite_compare.jpg``: frame 0's hybrid | full-spectral | CIEDE2000 sheet (``.../0000/compare.png``);
- ``fit_kite_all_orders.jpg``: the kite fit's contact sheet (``fit/kite/contact_sheet.png``) at 2/3 of its size;
- ``shot_day_to_sunset_filmstrip.png``, ``shot_sunset_mie_filmstrip.png``: the shots' ``filmstrip.png`` as they
  are;
- ``shot_day_to_sunset.gif``: the shot's frames (``shots/day_to_sunset/frames/*.png``) at half size, at the shot's
  ``fps`` from ``config/config.yaml``;
- ``textures_<name>.jpg``: each ``textures/<name>/compare.png`` the docs show, and ``textures_wood_completion.jpg``
  from ``textures/wood/completion_compare.png``.

JPEG quality 90 (OpenCV). Nothing is written unless every source exists. ``shot_day_cloud_unitless_vs_physical.png``
(the day frame's cloud with the sigma_t normalised per volume and at the physical extinction, both under the
earlier day sun at azimuth 120) is kept as it is: no config makes either half any more.
"""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from natscene.config import load_yaml_config, validate_config

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"
TEXTURES = ("meadow", "wood", "wood_colour", "wood_recolour", "moss", "moss_soft")


def _jpeg(image: np.ndarray, dest: Path) -> None:
    cv2.imwrite(str(dest), image, [cv2.IMWRITE_JPEG_QUALITY, 90])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default=str(ROOT / "results"), help="the main job's results folder")
    res = Path(ap.parse_args(argv).results)
    comp = res / "composite" / "day_to_sunset"
    frames = sorted((res / "shots" / "day_to_sunset" / "frames").glob("[0-9][0-9][0-9][0-9].png"))
    sources = [comp / "0000" / "final.png", comp / "0023" / "final.png", comp / "0000" / "compare.png",
               res / "shots" / "day_to_sunset" / "filmstrip.png", res / "shots" / "sunset_mie" / "filmstrip.png",
               res / "textures" / "wood" / "completion_compare.png", res / "fit" / "kite" / "contact_sheet.png",
               *(res / "textures" / t / "compare.png" for t in TEXTURES)]
    missing = [str(p) for p in sources if not p.is_file()] + ([] if frames else ["shots/day_to_sunset/frames/*.png"])
    if missing:
        print(f"doc_images: missing {missing}; run make run first", file=sys.stderr)
        return 1
    day, dusk = (cv2.imread(str(comp / f / "final.png")) for f in ("0000", "0023"))
    gap = np.full((day.shape[0], 8, 3), 255, np.uint8)
    _jpeg(np.concatenate([day, gap, dusk], 1), IMG / "composite_day_to_sunset.jpg")
    detail = np.concatenate([day[250:480, 0:330], day[170:400, 310:640]], 1)
    cv2.imwrite(str(IMG / "composite_detail.png"), cv2.resize(detail, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST))
    _jpeg(cv2.imread(str(comp / "0000" / "compare.png")), IMG / "composite_compare.jpg")
    sheet = cv2.imread(str(res / "fit" / "kite" / "contact_sheet.png"))
    _jpeg(cv2.resize(sheet, None, fx=2 / 3, fy=2 / 3, interpolation=cv2.INTER_AREA), IMG / "fit_kite_all_orders.jpg")
    for shot in ("day_to_sunset", "sunset_mie"):
        shutil.copyfile(res / "shots" / shot / "filmstrip.png", IMG / f"shot_{shot}_filmstrip.png")
    cfg = validate_config(load_yaml_config(ROOT / "config" / "config.yaml"),
                          ROOT / "workflow" / "schemas" / "config.schema.yaml")
    fps = cfg["shots"]["day_to_sunset"]["fps"]
    half = [Image.open(f).convert("RGB").reduce(2) for f in frames]
    half[0].save(IMG / "shot_day_to_sunset.gif", save_all=True, append_images=half[1:], duration=int(1000 / fps),
                 loop=0)
    for t in TEXTURES:
        _jpeg(cv2.imread(str(res / "textures" / t / "compare.png")), IMG / f"textures_{t}.jpg")
    _jpeg(cv2.imread(str(res / "textures" / "wood" / "completion_compare.png")), IMG / "textures_wood_completion.jpg")
    print(f"doc_images: {len(TEXTURES) + 8} images from {res} -> {IMG}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
