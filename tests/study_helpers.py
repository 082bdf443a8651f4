"""Tiny study files for the study tests (n = 2-3, short horizons, cheap models)."""

from pathlib import Path

TINY = """
[study]
name = "tiny"
reference = "{reference}"

[scene]
based_on = "paper"
n = 2
t_end = 0.1
times = {{ num = 11 }}

[integrator]
method = "DOP853"
rtol = 1e-7
atol = 1e-9

{models}

[grid]
scene.n = [2, 3]
{grid}
"""

CHEAP_MODELS = """
[models.reduced]
[models.published]
model = "reduced"
coefficients = "published"
"""


def write_study(
    tmp: Path,
    name: str = "tiny.toml",
    *,
    reference: str = "reduced",
    models: str = CHEAP_MODELS,
    grid: str = "scene.t_end = [0.1, 0.2]",
) -> Path:
    path = tmp / name
    path.write_text(TINY.format(reference=reference, models=models, grid=grid))
    return path
