"""SVG text with `rotate` lists uploaded to a real server: the job's preview draws each
glyph turned about its own start point, and a bad list is a warning on the job."""

from __future__ import annotations

import pytest

from tests.fixtures.text_glyphs import I_ADVANCE, i_pose

pytestmark = pytest.mark.e2e

SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"
     viewBox="0 0 100 100" font-size="32" font-family="Hershey Sans">
  <text x="10" y="50" rotate="90 -45">II<tspan rotate="30">I</tspan>I</text>
  <text id="bad" x="10" y="90" rotate="15 steep">I</text>
</svg>
"""


def test_rotated_glyphs_upload_and_a_bad_list_is_a_job_warning(server_virtual):
    response = server_virtual.client.post(
        "/api/jobs", files={"file": ("rotated.svg", SVG)}, data={"optimize": "false"})
    assert response.status_code == 201, response.text
    job = response.json()
    assert any('<text id="bad"> skipped' in w["message"]
               and "'steep' is not a number" in w["message"] for w in job["warnings"]), job
    strokes = server_virtual.preview(job["id"])["strokes"]
    # the preview is in machine mm (y up, placed on the bed): flip y, then compare the
    # glyphs with the first one
    poses = [i_pose(*((x, -y) for x, y in (s[0], s[-1]))) for s in strokes]
    x0, y0, _ = poses[0]
    got = [(round(x - x0, 2), round(y - y0, 2), angle) for x, y, angle in poses]
    # the text's last angle (-45) covers the glyph after the tspan's own 30
    assert got == [(0, 0, 90), (I_ADVANCE, 0, -45), (2 * I_ADVANCE, 0, 30),
                   (3 * I_ADVANCE, 0, -45)]
