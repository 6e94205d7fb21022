"""Batches: the inputs of a run (``inputs``) and the engine that runs work over them in order,
in forked worker processes or on a Dask cluster (``runner``, ``workers``). Library code: the
command line's progress bar, tally and summary live in ``p3d_cli.cli.reporting``."""

from p3d_cli.batch.inputs import collect_inputs, expand_inputs, read_file_list
from p3d_cli.batch.runner import ClusterLost, Outcome, default_jobs, run_each

__all__ = ["ClusterLost", "Outcome", "collect_inputs", "default_jobs", "expand_inputs", "read_file_list", "run_each"]
