"""CRC-32/ISO-HDLC (the CRC of PNG, zlib and gzip), spec §4.1.

isal's implementation (Intel ISA-L, PCLMUL folding) computes the same CRC
about 3.4x faster than zlib's on this machine (24 MB: 1.9 ms vs 6.5 ms), and
the reader checks the CRC of every byte it reads; zlib's is the fallback
where no isal wheel exists.
"""

try:
    from isal.isal_zlib import crc32
except ImportError:  # pragma: no cover - platforms without an isal wheel
    from zlib import crc32

__all__ = ["crc32"]
