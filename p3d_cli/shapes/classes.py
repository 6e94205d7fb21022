"""The shape classes, in the order help and messages list them: the one list of shapes.

``SHAPES`` (spec name -> class), spec parsing, the help's and the messages' lists, mirror
symmetry and the public names ``p3d.Box``... are all built from these classes and what each
declares (``p3d_cli.shapes.record``). A new shape is a module of ``shapes/`` and one line here.
"""

from p3d_cli.shapes.box import Box as Box
from p3d_cli.shapes.wedge import Wedge as Wedge
from p3d_cli.shapes.corner import Corner as Corner
from p3d_cli.shapes.cylinder import Cylinder as Cylinder
from p3d_cli.shapes.sphere import Sphere as Sphere
from p3d_cli.shapes.ellipsoid import Ellipsoid as Ellipsoid
from p3d_cli.shapes.elliptic_cylinder import EllipticCylinder as EllipticCylinder
from p3d_cli.shapes.capsule import Capsule as Capsule
