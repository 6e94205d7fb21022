"""``p3d robot``: check and fill the inertials of URDF, MJCF and SDF robot descriptions."""

from __future__ import annotations

import functools
import sys

import click

from p3d_cli.cli import output
from p3d_cli.cli.options import Quantity
from p3d_cli.errors import P3DError, UsageError

#: The robot library's parameter names as this command's flags (the rest: main.FLAGS).
_FLAGS = {"open_mesh": "--open-mesh",
          "package_paths": "--package-path", "density_range": "--density-range", "mass_from": "--mass-from",
          "masses": "--masses", "xacro_args": "--xacro-arg"}


def _flagged(command):
    """Report the robot library's parameter names (``where``, and ``name=`` in the text) as this
    command's flags."""
    @functools.wraps(command)
    def run(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except P3DError as exc:
            raise type(exc)(_FLAGS.get(exc.where, exc.where), _as_flags(exc.what), _as_flags(exc.hint)) from None
    return run


def _as_flags(text: str) -> str:
    """The library's parameter names in ``text`` (``open_mesh=hull``) as this command's flags."""
    text = text.replace("in_place=True", "--in-place").replace("force fills", "--force fills")
    for name, flag in _FLAGS.items():
        text = text.replace(f"{name}=", f"{flag} ")
    return text


def _package_option(f):
    f = click.option("--xacro-arg", "xacro_args", multiple=True, metavar="NAME:=VALUE",
                     help="An argument of a xacro file (repeatable), as on xacro's command line.")(f)
    return click.option("--package-path", "package_paths", multiple=True, metavar="NAME=DIR",
                        help="Folder of the package that package://NAME/... (SDF: model://NAME/...) URIs "
                             "and xacro's $(find NAME) name (repeatable); then ROS_PACKAGE_PATH "
                             "(GZ_SIM_RESOURCE_PATH) is searched, then the folders above the description "
                             "(a package.xml naming NAME, or a folder NAME).")(f)


def _open_mesh_option(f):
    return click.option("--open-mesh", "open_mesh", type=click.Choice(["refuse", "shell", "hull"]), default="refuse",
                        show_default=True,
                        help="What stands in for a mesh that bounds no solid (open, non-manifold, inward): "
                             "nothing; a thin shell of the link's mass over its surface; or the mesh's "
                             "convex hull (needs scipy: p3d's extra 'robots').")(f)


def _from_option(f):
    return click.option("--from", "role", type=click.Choice(["collision", "visual"]), default="collision",
                        show_default=True, help="Which geometry of each link to measure.")(f)


@click.group()
def robot() -> None:
    """Check and fill the <inertial> of every link of a URDF, MJCF or SDF description.

    A link is measured as an assembly of its collision geometry (or --from visual): each
    mesh (STL, OBJ, PLY, DAE in its declared unit, ... at its origin, with its scale, mirrored
    if negative) and each primitive (box, cylinder, sphere, capsule, ellipsoid) in the link
    frame. Descriptions are in SI (m, kg). xacro files are expanded when the xacro package is
    installed (p3d's extra 'robots'). See docs/robots.md.

    \b
    Examples:
      p3d robot check robot.urdf --package-path my_robot=./my_robot
      p3d robot fill robot.urdf --density 2.7g/cm^3 -o filled.urdf
      p3d props link.stl --units mm --density 2.7g/cm^3 --emit urdf
    """


@robot.command()
@click.argument("description", metavar="FILE")
@_package_option
@click.option("--from", "role", type=click.Choice(["auto", "collision", "visual"]), default="auto",
              show_default=True, help="Which geometry to compare each inertial with; auto: the closer match of "
                                      "the two (said in the verdict).")
@click.option("--require-inertial", is_flag=True, help="Fail links that have geometry but declare no inertial.")
@_open_mesh_option
@click.option("--tolerance", type=click.FloatRange(min=1, min_open=True), default=2.0, show_default=True,
              metavar="FACTOR", help="Allowed factor between each declared principal moment and the "
                                     "geometry's at the declared mass (real links are not uniform).")
@click.option("--density-range", default="50,25000", show_default=True, metavar="LOW,HIGH",
              help="Plausible implied densities (declared mass / geometry volume), kg/m^3.")
@click.option("--com-slack", type=click.FloatRange(min=0), default=0.05, show_default=True, metavar="FRACTION",
              help="How far outside the geometry's bounds a centre of mass may lie, as a fraction "
                   "of their diagonal.")
@click.option("--json", "as_json", is_flag=True, help="One JSON record per link.")
@click.option("--report", "report", default=None, metavar="html:DIR",
              help="Also write DIR/index.html (pictures in DIR/images/): each link's geometry with its declared "
                   "and computed inertia drawn together, failed links first, with the numbers.")
@click.option("--report-shape", "shape", type=click.Choice(["box", "ellipsoid"]), default="box", show_default=True,
              help="The uniform solid the report draws for each inertia.")
@_flagged
def check(description, package_paths, xacro_args, role, require_inertial, open_mesh, tolerance, density_range,
          com_slack, as_json, report, shape):
    """Check every link's declared inertial: possible, and consistent with its geometry.

    Rules: mass > 0; the inertia symmetric and positive definite; principal moments obeying
    the triangle inequality (I1 + I2 >= I3); the centre of mass inside the geometry's bounds;
    and, where the geometry is a closed solid, the declared moment about each of the
    geometry's principal axes within --tolerance of the geometry's at the declared mass (so a
    tensor about the wrong axis fails) and the implied density within --density-range (this
    catches mm/m and g/kg slips). Links of at most 1 g are massless frames: reported, not
    failed. One line per problem on stdout, with the geometry, density and tolerance used.

    --report html:DIR also writes a page to look at: per link, its geometry in the link frame
    with two equivalent uniform boxes (same mass and principal moments), the declared one in
    raspberry and the computed one in teal, its verdict and numbers; failed links first. It
    stands alone (no network; open DIR/index.html). See docs/render.md.

    \b
    Exit statuses: 0 every link passes; 1 some link fails; 2 the description (or a mesh it
    names) cannot be read, or the report cannot be written.

    \b
    Examples:
      p3d robot check robot.urdf --package-path my_robot=./my_robot
      p3d robot check scene.xml --json
      p3d robot check robot.urdf --report html:inertia-report
    """
    from p3d_cli.robots import check_robot, load_robot

    low_high = _range(density_range)
    folder = _report_folder(report)
    robot_ = load_robot(description, package_paths, xacro_args)
    if folder is not None:
        from p3d_cli.render.robot_page import check_folder
        from p3d_cli.robots.fill import description_files

        check_folder(folder, description_files(robot_))
    for note in robot_.notes:
        click.echo(f"p3d: warning: {robot_.path}: {note}", err=True)
    checks = check_robot(robot_, tolerance=tolerance, role=role, com_slack=com_slack, density_range=low_high,
                         require_inertial=require_inertial, open_mesh=open_mesh)
    for c in checks:
        if as_json:
            click.echo(output.formatted("robot", _record(robot_.path, c), "json"))
            continue
        for p in c.problems:
            click.echo(f"{robot_.path}: link {c.link!r}: {p.message} (rule: {p.rule}; from {c.basis})")
    if folder is not None:
        from p3d_cli.render.robot_page import write_robot_report

        write_robot_report(robot_, checks, folder, shape=shape, role=role)
    failed = [c.link for c in checks if not c.ok]
    frames = sum(1 for c in checks if c.status == "frame")
    if not as_json:
        tally = (f"{output.plural(len(checks), 'link')}, {len(failed)} failed"
                 + (f", {output.plural(frames, 'massless frame')}" if frames else "")
                 + (f": {', '.join(failed)}" if failed else ""))
        click.echo(f"p3d robot check: {robot_.path}: {tally}", err=True)
    return 1 if failed else 0


def _report_folder(value: str | None) -> str | None:
    """The folder of ``--report html:DIR`` (the spelling of the other commands' ``--report``)."""
    if value is None:
        return None
    kind, _, folder = value.partition(":")
    if kind != "html" or not folder:
        raise UsageError("--report", f"{value!r} is not a report p3d robot check writes", "use html:DIR (a folder)")
    return folder


def _range(text: str) -> tuple[float, float]:
    try:
        low, high = (float(x) for x in text.split(","))
    except ValueError:
        low = high = float("nan")
    if not 0 < low < high < float("inf"):
        raise UsageError("--density-range", f"{text!r} is not LOW,HIGH with 0 < LOW < HIGH",
                         "give e.g. 50,25000 (kg/m^3)")
    return low, high


def _record(path: str, c) -> dict:
    return {"source": path, "link": c.link, "ok": c.ok, "status": c.status,
            "problems": [{"rule": p.rule, "value": p.value, "message": p.message} for p in c.problems],
            "notes": c.notes, "geometry": c.geometry, "implied_density": c.implied_density,
            "tolerance": c.tolerance, "open_mesh": c.stand_in, "moment_ratios": c.moment_ratios}


@robot.command()
@click.argument("description", metavar="FILE")
@_package_option
@_from_option
@click.option("--density", type=Quantity(), default=None,
              help="Density of every link's geometry: kg/m^3 bare, or with a unit (2.7g/cm^3).")
@click.option("--mass-from", "mass_from", type=click.Choice(["declared"]), default=None,
              help="Keep each link's declared mass; recompute only its centre of mass and inertia.")
@click.option("--masses", "masses", default=None, metavar="YAML",
              help="A YAML mapping of link names to masses (kg bare, or with a unit: 500 g); wins "
                   "over --mass-from and --density.")
@click.option("--force", is_flag=True, help="Also fill links whose geometry is open, flat or inward-wound.")
@_open_mesh_option
@click.option("--principal", is_flag=True,
              help="MJCF: write quat + diaginertia (the principal frame) instead of fullinertia.")
@click.option("-o", "--output", "out", default=None, metavar="OUT",
              help="Write the filled description here (- or nothing: stdout); never the description itself.")
@click.option("--in-place", is_flag=True,
              help="Rewrite the description itself (and the files it includes that hold filled "
                   "inertials): each through a temporary file renamed over it when complete.")
@_flagged
def fill(description, package_paths, xacro_args, role, density, mass_from, masses, force, open_mesh, principal,
         out, in_place):
    """Write the description with each link's <inertial> computed from its geometry.

    URDF gets origin xyz (rpy 0) and the full ixx..izz in the link frame; MJCF pos, mass and
    fullinertia in the body frame (--principal: quat and diaginertia); SDF pose and inertia.
    Every other byte of the file is left as it was (comments, CDATA, entities, encoding, line
    endings), and a second run changes nothing. A link whose geometry is open, flat,
    inward-wound or missing keeps its declared inertial (reported on stderr) unless --force.
    MJCF geoms keep their own density or mass (MuJoCo's default density 1000 kg/m^3 when
    neither they nor --density say one).

    Files are written whole or not at all: to a temporary file in the same folder, renamed
    over the target when complete, with the target's permissions; a read-only or hard-linked
    target is refused.

    \b
    Examples:
      p3d robot fill robot.urdf --density 2700 -o filled.urdf
      p3d robot fill robot.urdf --mass-from declared --in-place
      p3d robot fill scene.xml --masses masses.yaml --density 1.2g/cm^3 > filled.xml
    """
    from p3d_cli.robots import fill_robot, load_masses, load_robot

    robot_ = load_robot(description, package_paths, xacro_args)
    for note in robot_.notes:
        click.echo(f"p3d: warning: {robot_.path}: {note}", err=True)
    table = load_masses(masses) if masses else None
    result = fill_robot(robot_, role=role, density=density, mass_from=mass_from, masses=table, force=force,
                        principal=principal, open_mesh=open_mesh)
    for link in result.links:
        if link.status == "kept":
            click.echo(f"p3d: warning: {robot_.path}: link {link.link!r}: left as it was: "
                       f"{_as_flags(link.reason)}", err=True)
        elif link.reason:
            click.echo(f"p3d: warning: {robot_.path}: link {link.link!r}: {link.reason}", err=True)
    written = write_filled(robot_, result, out, in_place)
    filled = sum(1 for link in result.links if link.status == "filled")
    where = "" if not in_place else f" ({', '.join(written)} rewritten in place)" if written else \
        " (nothing changed, nothing rewritten)"
    click.echo(f"p3d robot fill: {robot_.path}: {filled} of {len(result.links)} links filled{where}", err=True)
    return 0


def write_filled(robot_, result, out, in_place: bool) -> list[str]:
    """Write a fill's result: to stdout, to ``out``, or every changed file in place; returns the
    paths written."""
    from p3d_cli.robots.fill import write_fill

    if in_place and out is not None:
        raise UsageError("--in-place", "given with --output", "give one of them")
    if not in_place and out in (None, "-"):
        others = sorted(set(result.files) - {robot_.doc.path})
        if others:
            raise UsageError("--output", f"filled inertials are in included files too ({', '.join(others)}), "
                             "which one output cannot hold", "give --in-place to rewrite each file")
        sys.stdout.flush()
        sys.stdout.buffer.write(result.data)
        sys.stdout.buffer.flush()
        return []
    return write_fill(robot_, result, None if in_place else out)
