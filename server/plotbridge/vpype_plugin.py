"""The `plotbridge` command for vpype: send the current document to a plotbridge server.

    vpype read art.svg linemerge linesort plotbridge --url http://plotter.local:8000 \\
        --paper a4 --start --wait

Installed with `pip install "plotbridge[vpype]"` (entry point `vpype.plugins`).
The document goes up as an SVG whose Inkscape layers are vpype's layers, each
with its name, colour and pen width, so the server keeps them apart.
"""

from __future__ import annotations

from typing import Any
from xml.sax.saxutils import quoteattr

import click
import vpype as vp
import vpype_cli

from plotbridge.client import Plotbridge, PlotbridgeError
from plotbridge.progress import job_progress

MM_PER_PX = 25.4 / 96  # vpype works in CSS pixels
DEFAULT_PEN_WIDTH_PX = 0.3 / MM_PER_PX


def _path_data(line: Any) -> str:
    points = " ".join(f"{p.real:.3f},{p.imag:.3f}" for p in line)
    return f"M {points}"


def document_svg(document: vp.Document) -> str:
    """The document as SVG: page size in mm, one Inkscape layer group per vpype layer."""
    if document.page_size is not None:
        width, height = document.page_size
        origin = (0.0, 0.0)
    else:
        bounds = document.bounds() or (0.0, 0.0, 1.0, 1.0)
        origin = (bounds[0], bounds[1])
        width, height = max(bounds[2] - bounds[0], 1.0), max(bounds[3] - bounds[1], 1.0)
    out = [
        '<svg xmlns="http://www.w3.org/2000/svg" '
        'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        f'width="{width * MM_PER_PX:.4f}mm" height="{height * MM_PER_PX:.4f}mm" '
        f'viewBox="{origin[0]:.3f} {origin[1]:.3f} {width:.3f} {height:.3f}">'
    ]
    for layer_id in sorted(document.layers):
        layer = document.layers[layer_id]
        name = layer.property(vp.METADATA_FIELD_NAME) or f"layer {layer_id}"
        color = layer.property(vp.METADATA_FIELD_COLOR)
        colour = color.as_hex()[:7] if color is not None else "#000000"
        pen_width = layer.property(vp.METADATA_FIELD_PEN_WIDTH) or DEFAULT_PEN_WIDTH_PX
        out.append(
            f'<g inkscape:groupmode="layer" id="layer{layer_id}" inkscape:label={quoteattr(name)}'
            f' fill="none" stroke="{colour}" stroke-width="{pen_width:.4f}">'
        )
        out += [f'<path d="{_path_data(line)}"/>' for line in layer.lines if len(line) > 0]
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out)


@click.command()
@click.option("--url", envvar="PLOTBRIDGE_URL", help="server URL (default: found on the LAN)")
@click.option("--token", envvar="PLOTBRIDGE_TOKEN", help="API token")
@click.option("--token-file", envvar="PLOTBRIDGE_TOKEN_FILE", help="file holding the token")
@click.option("--name", default="vpype", show_default=True, help="job name")
@click.option("--paper", help="paper to centre the drawing on: A6..A3, letter (-landscape)")
@click.option("--margin", type=float, help="paper margin, mm")
@click.option("--fit", is_flag=True, default=None, help="scale the drawing to fill the paper")
@click.option("--plotter", help="plotter to run it on (default: any)")
@click.option("--start", is_flag=True, help="start the job after the upload")
@click.option("--wait", is_flag=True, help="follow the job with a progress bar until it ends")
@vpype_cli.global_processor
def plotbridge(document: vp.Document, url: str | None, token: str | None,
               token_file: str | None, name: str, paper: str | None, margin: float | None,
               fit: bool | None, plotter: str | None, start: bool, wait: bool) -> vp.Document:
    """Send the document to a plotbridge server, each layer a plotbridge layer."""  # fmt: skip
    if document.is_empty():
        raise click.ClickException("plotbridge: the document is empty, nothing to plot")
    try:
        with Plotbridge(url, token, token_file=token_file) as pb:
            svg = document_svg(document).encode()
            job = pb.upload(svg, filename=f"{name}.svg", name=name, plotter=plotter,
                            start=start, paper=paper, margin=margin, fit=fit)  # fmt: skip
            if wait:
                with job_progress(name) as update:
                    job = pb.wait(job["id"], update)
    except PlotbridgeError as exc:
        raise click.ClickException(f"plotbridge: {exc}") from exc
    estimate = job.get("estimate_s") or 0
    click.echo(f"plotbridge: job {job['id']} {job['state']}, estimate {estimate:.0f} s", err=True)
    if wait and job["state"] != "done":
        raise click.ClickException(f"plotbridge: job {job['id']} ended {job['state']}: "
                                   f"{job.get('error') or ''}")  # fmt: skip
    return document
