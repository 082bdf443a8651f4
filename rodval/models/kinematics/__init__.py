"""Kinematics and shapes: the model ladder (shapes p per rod, first-order or exact kinematics) and
its rungs."""
