"""The part-group kinds: how a body becomes planes and how each kind's planes become triangles.

Convex cells (``cells``), BSP trees (``bsptree``, ``exactbsp``, ``solids``, ``seams``), pseudo-convex
and pseudo-concave patches (``patches``), sealed groups (``sealed``), shells (``shells``), and
``bodies``, which picks a kind for a non-convex body. Built on ``planefmt.geometry``; reads the
container's records only where a kind's fields are coded (shell corners).
"""
