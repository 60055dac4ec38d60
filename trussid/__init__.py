"""trussid: the command line and the end-to-end pipeline composing `geometry`, `fem`, `plid`.

This package's ``__init__`` stays import-light on purpose: the lower packages may import
:mod:`trussid.errors` and :mod:`trussid.files` (standard library only) without pulling in
the pipeline.
"""

__version__ = "0.1.0"
