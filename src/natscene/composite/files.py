"""
Files of a composite frame
==========================

Defines the files a frame of a ``composite.<name>`` entry reads, from its config alone (no image is opened):
the ``composite`` rule's inputs, known when the workflow is parsed, and the paths
:mod:`natscene.composite.inputs` loads.

-   :func:`input_files`: every file a frame reads.
-   :func:`image_files`: the file(s) of one image source (``product``, ``path``; none for synthetic ones).
-   :func:`shot_files`, :func:`pattern_product`: a shot's frame products, a pattern's colour map.

Light on purpose (paths only): Snakemake imports it for every dry run.

References
----------
-   Dong, W. (2007). Rendering Algorithms for Natural Scenes. PhD thesis, Université Henri Poincaré - Nancy I.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["input_files", "image_files", "shot_files", "pattern_product"]


def input_files(entry: dict, frame: int, results: str, root: str, shot_cfg: dict | None = None) -> list[str]:
    """Every file a composite frame reads (for the rule's input)."""
    files = []
    if entry.get("shot"):
        files += list(shot_files(entry["shot"], shot_cfg["volume"], frame, results).values())
    else:
        files += image_files(entry["background"], frame, results, root)
    files += image_files(entry["ground"]["texture"], frame, results, root)
    meadow = entry.get("meadow") or {}
    for f in meadow.get("flowers", []):
        files += image_files(pattern_product(f["pattern"]), frame, results, root)
    for src in (meadow.get("leaves") or {}).get("textures", []):
        files += image_files(src, frame, results, root)
    if entry["sun"].get("sky_product"):
        files.append(str(Path(results) / entry["sun"]["sky_product"]))
    return files


def image_files(source: dict, frame: int, results: str, root: str) -> list[str]:
    """The file(s) an image source reads (empty for synthetic sources)."""
    if "product" in source:
        return [str(Path(results) / source["product"].format(frame=frame))]
    if "path" in source:
        p = Path(source["path"].format(frame=frame))
        return [str(p if p.is_absolute() else Path(root) / p)]
    return []


def pattern_product(pattern: str) -> dict:
    """The image source of a pattern's colour map (``patterns/<pattern>/color.exr``, alpha = the petal's outline)."""
    return {"product": f"patterns/{pattern}/color.exr"}


def shot_files(shot: str, volume: str, frame: int, results: str) -> dict:
    """The shot's products that frame ``frame`` of a composite reads: its state, its cloud plate, its volume's meta."""
    r = Path(results)
    return {"state": str(r / f"shots/{shot}/params/{frame:04d}.yaml"),
            "plate": str(r / f"shots/{shot}/frames/{frame:04d}.exr"),
            "volume": str(r / f"volumes/{volume}/meta.yaml")}
