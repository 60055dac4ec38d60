"""Identification from input/output data: PLID, experiments, FRF estimates, metrics, grey-box.

Works on numpy arrays and ``control.StateSpace``; never imports ``fem`` or ``geometry``.
"""
