"""The container: the bytes of a .pln file and nothing of their geometry.

Construct declarations (``schema``), chunk framing (``chunks``, ``crc``),
varints, typed records, plane triplet codings (``quantize``), the streaming
``reader`` and ``writer``, ``salvage`` of damaged files and ``validate``.
Imports only ``planefmt.errors`` and ``planefmt.model`` from the rest of
planefmt.
"""
