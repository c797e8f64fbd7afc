"""Plane geometry: plane math, exact predicates, half-space intersection, polytopes, clipping,
polygonization, triangle distances and the certified Hausdorff distance.

Knows nothing of files or part groups: imports only ``planefmt.errors`` from the rest of planefmt.
"""
