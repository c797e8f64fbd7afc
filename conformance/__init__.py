"""The .pln conformance suite: golden files, their generator, and a runner for any implementation (README.md)."""
