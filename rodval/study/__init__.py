"""Studies: a grid of scenes x models described in a TOML file, run in parallel and resumable.

spec (parse and validate) -> schedule (warm worker processes or dask) -> records (one
verified file per finished case, in a store) -> tables (pandas, CSV and markdown) -> report
(``rodval.report``); ``pipeline.run_study`` runs them in that order.
"""

from rodval.study.case import Case
from rodval.study.model_specs import ModelSpec
from rodval.study.pipeline import StudyRun, run_study
from rodval.study.spec import StudySpec, load_study, study_from_dict
from rodval.study.tables import build_tables, write_tables

__all__ = [
    "Case",
    "ModelSpec",
    "StudySpec",
    "StudyRun",
    "load_study",
    "study_from_dict",
    "run_study",
    "build_tables",
    "write_tables",
]
