"""Identification and compensation: one module per published procedure.

Each module reproduces its paper's measurement plan and formulas on virtual measurements
only (never the injected errors: the honesty rule of DESIGN.md), and rewrites the NC program
to compensate what it identified.
"""
