"""Reference models of the rod chain that share nothing with the paper's equations.

``exudyn_chain.ExudynModel`` (model name ``exudyn``): each rod meshed into ANCF cable
elements in exudyn. Only rodval's scene, load, settings, trajectory and model-interface types
are imported here, never the paper's matrices or models: independence is the point.
"""
