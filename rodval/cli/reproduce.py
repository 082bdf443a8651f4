"""rodval reproduce paper --out DIR: the paper's Table 1 and Fig. 3."""
from __future__ import annotations

from pathlib import Path

from ..reproduce import reproduce_paper


def register(sub) -> None:
    p = sub.add_parser("reproduce", help="reproduce the paper's example (Table 1, Fig. 3)",
                       description="Run the paper's example with the full and reduced models "
                                   "and write DIR/table1.csv, DIR/table1.md, DIR/configurations.png.")
    p.add_argument("target", choices=("paper",), help="what to reproduce")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument("--variant", choices=("printed", "published"), default="printed",
                   help="coefficients: printed (from the kinematics, default) or published "
                        "(the erratum that reproduces the paper's alpha/beta)")
    p.set_defaults(func=run)


def run(args) -> int:
    errors = reproduce_paper(args.out, args.variant)
    wide = errors.pivot_table(index=["quantity", "formulation"], columns="t", values="error",
                              sort=False)
    print(f"Table 1 column errors (max_k |rodval - published| / max_k |published|), "
          f"coefficients = {args.variant}:")
    print(wide.to_string(float_format=lambda v: f"{v:.2e}"))
    print(f"wrote {args.out}/table1.csv, table1.md, configurations.png")
    return 0
