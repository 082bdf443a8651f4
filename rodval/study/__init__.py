"""Studies: a grid of scenes x models described in a TOML file, run in parallel and resumable.

spec (parse and validate) -> runner (cases in worker processes or on dask, one file per
finished case) -> tables (pandas, CSV and markdown) -> ``rodval.report``.
"""
from .runner import StudyRun, run_study
from .spec import Case, ModelSpec, StudySpec, load_study, study_from_dict
from .tables import build_tables, write_tables

__all__ = ["Case", "ModelSpec", "StudySpec", "StudyRun", "load_study", "study_from_dict",
           "run_study", "build_tables", "write_tables"]
