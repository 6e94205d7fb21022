"""Run ``p3d`` from a given source tree, whatever p3d is installed: ``python tree.py TREE ARGS...``.

An editable install (``pip install -e .``) puts a finder on ``sys.meta_path`` that answers for
``p3d_cli`` before ``sys.path`` is searched, so ``PYTHONPATH=TREE python -m p3d_cli`` silently
runs the installed tree instead of TREE. This drops such finders, puts TREE first on the path,
checks that ``p3d_cli`` comes from TREE, and runs the command line as ``python -m p3d_cli`` does.
The before/after benchmarks and ``same_results.py`` run each tree through it.
"""

import os
import runpy
import sys

tree = os.path.abspath(sys.argv.pop(1))
sys.meta_path[:] = [finder for finder in sys.meta_path if "editable" not in repr(finder)]
sys.path.insert(0, tree)
import p3d_cli  # noqa: E402

if not os.path.abspath(p3d_cli.__file__).startswith(tree + os.sep):
    raise SystemExit(f"tree.py: p3d_cli comes from {p3d_cli.__file__}, not from {tree}")
sys.argv[0] = "p3d"
runpy.run_module("p3d_cli", run_name="__main__")
