"""Preview labels (natscene.preview.label): the outlined label's black outline surrounds its own white text, on
any tile, and nothing else (a thicker second putText advances its glyphs further: a ghost of the last letters
beside the text)."""
import numpy as np
import pytest
from scipy import ndimage

from natscene.preview import label


@pytest.mark.parametrize("height", [240, 480, 960])
def test_the_outline_surrounds_the_text(height):
    grey = np.full((height, height * 4 // 3, 3), 128, np.uint8)
    out = label(grey.copy(), "#10 O=0.5633")
    text = (out > 150).all(-1)                     # the white text, its anti-aliased edge included
    dark = (out <= 60).all(-1)
    assert text.sum() > 50 and dark.sum() > 50
    # every dark pixel lies next to the text (its outline: a pixel wide around the anti-aliased stroke, which a 3 x 3
    # step from a faint edge pixel carries sqrt(5) px from the brighter ones), and nothing is painted farther away
    to_text = ndimage.distance_transform_edt(~text)
    assert to_text[dark].max() <= 5 ** 0.5 + 1e-6
    assert (out[to_text > 4] == 128).all()
    # and the text is outlined all along: its bounding box's ends carry the outline too
    cols_text, cols_dark = np.flatnonzero(text.any(0)), np.flatnonzero(dark.any(0))
    assert abs(cols_dark[0] - cols_text[0]) <= 2 and abs(cols_dark[-1] - cols_text[-1]) <= 2
