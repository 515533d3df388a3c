"""Robustness: a thousand (or PLOTBRIDGE_FUZZ_EXAMPLES) generated SVG documents (valid
and broken structure,
odd attribute values, references to nowhere and to themselves) are either imported or
refused with ImportFailed: no other exception, each within a time bound, memory
bounded."""

from __future__ import annotations

import os
import resource
import time

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plotbridge.importing import ImportFailed, ImportOptions
from plotbridge.importing.models import ErrorLog
from plotbridge.importing.svg import read_svg

TAGS = ["g", "path", "rect", "circle", "ellipse", "line", "polyline", "polygon", "use",
        "symbol", "defs", "clipPath", "mask", "switch", "svg", "text", "tspan", "textPath",
        "a", "style", "image", "foo", "marker"]
NUMBER = st.one_of(st.integers(-50, 300).map(str), st.floats(-1e6, 1e6).map(repr),
                   st.sampled_from(["", "nan", "inf", "-0", "1e308", "50%", "3mm", "2em",
                                    "abc", "auto", "1 2", "0"]))
PATH = st.lists(st.one_of(st.sampled_from(list("MLHVCSQTAZmlhvcsqtaz")), NUMBER),
                max_size=20).map(" ".join)
ATTR = st.one_of(
    st.tuples(st.sampled_from(["x", "y", "width", "height", "r", "rx", "ry", "cx", "cy",
                               "x1", "y1", "x2", "y2", "stroke-width", "opacity",
                               "startOffset", "font-size", "dx", "dy"]), NUMBER),
    st.tuples(st.just("d"), PATH),
    st.tuples(st.just("points"), st.lists(NUMBER, max_size=10).map(",".join)),
    st.tuples(st.sampled_from(["transform"]),
              st.sampled_from(["rotate(30)", "scale(0)", "matrix(1 2 3)", "translate(",
                               "skewX(89.9999)", "scale(1e300)", "rotate(a)"])),
    st.tuples(st.sampled_from(["href", "clip-path", "mask", "id", "marker-start", "marker-mid",
                               "marker-end", "marker"]),
              st.sampled_from(["#a", "#b", "url(#a)", "url(#b)", "a", "b", "#", "url(#"])),
    st.tuples(st.sampled_from(["stroke", "fill", "style", "viewBox", "fill-rule",
                               "systemLanguage", "text-anchor", "display", "visibility"]),
              st.sampled_from(["black", "none", "red", "url(#a)", "currentColor",
                               "stroke:blue;fill:none", "0 0 10 10", "0 0 0 0", "evenodd",
                               "en", "middle", "none", "hidden", "rgba(0,0,0,0)", ";;:",
                               "transform: rotate(30deg)", "stroke: red !important",
                               "font-size: 2em"])),
)
NAMES = {"stroke", "fill", "style", "viewBox", "fill-rule", "systemLanguage", "text-anchor",
         "display", "visibility", "href", "clip-path", "mask", "id", "transform", "d",
         "points"}


def element(children):
    return st.builds(
        lambda tag, attrs, kids, text: (
            f"<{tag} " + " ".join(f'{k}="{v}"' for k, v in dict(attrs).items()) + ">"
            + (text or "") + "".join(kids) + f"</{tag}>"),
        st.sampled_from(TAGS), st.lists(ATTR, max_size=6), st.lists(children, max_size=4),
        st.sampled_from(["", "Hi", "x y", "&amp;", "\u00e9\u4e2d"]))


DOCS = st.recursive(st.just(""), element, max_leaves=25).map(
    lambda body: '<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
                 f'viewBox="0 0 100 100">{body}'
                 '<line x1="1" y1="1" x2="9" y2="9" stroke="black"/></svg>')


# make test runs 1000 documents; PLOTBRIDGE_FUZZ_EXAMPLES=5000 for a longer run
@settings(max_examples=int(os.environ.get("PLOTBRIDGE_FUZZ_EXAMPLES", "1000")), deadline=None,
          database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(doc=DOCS)
def test_generated_svgs_import_or_are_refused(tmp_path, doc):
    """The SVG stage (parse, resolve, clip, hatch, flatten); what follows it is the same
    for every format and tested on its own."""
    src = tmp_path / "f.svg"
    src.write_text(doc, encoding="utf-8")
    start = time.monotonic()
    try:
        layers = read_svg(src, ImportOptions(fill="hatch"), ErrorLog())
        assert all(len(s) > 1 for lay in layers for s in lay.strokes)
    except ImportFailed as e:
        assert e.errors and all(err["message"] for err in e.errors)
    assert time.monotonic() - start < 20
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss < 1_500_000   # KiB
