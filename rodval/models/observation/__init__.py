"""Observation: linearized modes (pinned and free spacecraft) and static equilibria."""
