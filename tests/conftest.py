import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))


def pytest_configure(config):
    # pyproject.toml's [tool.pytest.ini_options] markers are owned elsewhere: register here
    config.addinivalue_line(
        "markers",
        "fuzz: hypothesis fuzzing of the command line (RODVAL_FUZZ_EXAMPLES=N for more)",
    )
