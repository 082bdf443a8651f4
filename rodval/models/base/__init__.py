"""The base node 0 belongs to: a free body (the paper rung's kernels and any rung's) and a
prescribed motion."""
