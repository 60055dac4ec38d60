"""The benchmark plants, now :mod:`trussid.study.plants` (studies use them by name)."""

from trussid.study.plants import (FS, PLANTS, Case, butterworth_inputs, case_a, case_b,  # noqa: F401
                                  case_testbed_like, modal_acceleration_plant, record)

__all__ = ["Case", "case_a", "case_b", "case_testbed_like", "record", "modal_acceleration_plant",
           "butterworth_inputs", "FS", "PLANTS"]
