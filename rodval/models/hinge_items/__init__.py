"""Hinge items: latches held as exact constraints, their plastic locks and lock records."""
