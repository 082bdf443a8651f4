"""The systems, assembled from the rooms below: the paper's systems' shared part
(``paper_system``), the chain systems (``chain_system``: a rung x a base's body x the hinge items)
and their kernel tables."""
