"""Leaf utilities shared by every layer: errors, atomic files, BLAS threads, JSON, lazy exports.

Imports nothing of trussid; every other subpackage may import it.
"""
