"""``p3d render``: a shaded picture of a mesh, shape or assembly, with overlays, to PNG or SVG."""

from __future__ import annotations

import click

from p3d_cli.cli import output
from p3d_cli.cli.options import FiniteFloat, format_option, json_option, placement_options
from p3d_cli.errors import UsageError
from p3d_cli.render.camera import UP_AXES, VIEWS
from p3d_cli.render.overlays import SHOW


class Size(click.ParamType):
    """``WIDTHxHEIGHT`` in pixels (``800x600``)."""

    name = "WxH"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        parts = str(value).lower().replace("*", "x").split("x")
        try:
            width, height = (int(p) for p in parts)
        except ValueError:
            self.fail(f"expected WIDTHxHEIGHT in pixels, such as 800x600, got {value!r}", param, ctx)
        return width, height


@click.command()
@click.argument("source", metavar="INPUT", type=click.Path())
@click.option("--output", "-o", metavar="FILE", type=click.Path(dir_okay=False), default=None,
              help="The picture to write: FILE.png or FILE.svg (replaced only when complete).")
@click.option("--svg", "as_svg", is_flag=True, help="Write SVG whatever FILE's extension.")
@click.option("--view", type=click.Choice(list(VIEWS)), default="iso", show_default=True,
              help="A standard view (orthographic; z up).")
@click.option("--azimuth", type=FiniteFloat(), default=None, metavar="DEGREES",
              help="Camera direction around the up axis: 0 front (from -y), 90 right (from +x), 180 back; "
                   "overrides --view's.")
@click.option("--elevation", type=FiniteFloat(), default=None, metavar="DEGREES",
              help="Camera height: 90 from above, -90 from below, 0 level; overrides --view's.")
@click.option("--up", type=click.Choice(list(UP_AXES)), default="z", show_default=True,
              help="The part's up axis (scans and game meshes are often y-up).")
@click.option("--size", type=Size(), default="800x600", show_default=True, metavar="WxH",
              help="Picture size in pixels, title and legend included.")
@click.option("--show", "show", multiple=True, metavar="WHAT[,WHAT...]",
              help="Overlays (repeatable or comma-separated): " + ", ".join(SHOW) + "; all (all but "
                   "ellipsoid).")
@click.option("--title", default=None, help="Title line (default: the input's name and triangle count).")
@format_option
@placement_options
@json_option
def render(source, output, as_svg, view, azimuth, elevation, up, size, show, title, fmt, placement, tessellate,
           as_json):
    """Draw a shaded picture of a mesh, shape or assembly: PNG or SVG, no display needed.

    Faces are hidden by a z-buffer (correct wherever faces overlap or cross), shaded under two
    lights with their outer side grey-blue and their inner side (seen through a hole, or wound
    against its neighbours) warm. Overlays, each in its own colour and named in the legend:
    defects (boundary, non-manifold and misoriented edges, degenerate faces, and
    self-intersections where p3d check reports them), axes (the principal frame at the centre
    of mass, lengths in proportion to the principal moments), inertia (the equivalent uniform
    box; ellipsoid for the ellipsoid), bounds (the axis-aligned box). Lines behind the part are
    drawn thin and dashed. SVG holds the surface as an embedded PNG and the overlays, title and
    legend as vectors (docs/render.md).

    \b
    Examples:
      p3d render part.stl -o part.png
      p3d render part.stl -o defects.png --show defects --view front
      p3d render part.stl -o frame.svg --show axes,inertia --azimuth 30 --elevation 20
      p3d render box:1,2,3 -o box.png --size 400x300
      p3d render assembly.yaml -o assembly.png --show bounds
    """
    from p3d_cli.render.files import picture_format, write_picture
    from p3d_cli.render.picture import picture

    if output is None:
        raise UsageError("--output", "no picture file named", "give -o FILE.png or -o FILE.svg")
    kind = picture_format(output, "svg" if as_svg else None)
    drawn = picture(source, view=view, azimuth=azimuth, elevation=elevation, up=up, size=size,
                             show=show, format=fmt, placement=placement, title=title, segments=tessellate)
    written = write_picture(drawn, output, format=kind, inputs=[source])
    if as_json:
        click.echo(output_record(drawn, str(written), kind))


def output_record(picture, path: str, kind: str) -> str:
    """The ``--json`` line: what was drawn where."""
    width, height = picture.size
    return output.formatted("render", {"output": path, "format": kind, "width": width, "height": height,
                                       "faces": picture.faces, "azimuth": picture.azimuth,
                                       "elevation": picture.elevation,
                                       "overlays": [{"name": layer.key, "label": layer.label}
                                                    for layer in picture.layers]}, "json")
