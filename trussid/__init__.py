"""trussid: beam FE, control-ready plants and PLID identification for piezo-actuated trusses.

One import root, layered (each layer imports only those before it; ``tests/test_layering.py``
enforces it):

- :mod:`trussid._util` - errors, atomic files, BLAS threads (a leaf);
- :mod:`trussid.fem` - generic 3-D frame finite elements (knows nothing of the testbed);
- :mod:`trussid.plid` - identification from data (never imports ``fem``);
- :mod:`trussid.geometry` - the testbed's parametric description and solids;
- :mod:`trussid.testbed` - the thesis testbed: FE model, walls, labels, lab chain, plant;
- :mod:`trussid.plots` - every figure, one style;
- :mod:`trussid.campaign`, :mod:`trussid.updating` - the demo and model updating;
- :mod:`trussid.cli` - the command line (nothing imports it).

This ``__init__`` stays import-light on purpose: it imports nothing.
"""

__version__ = "0.1.0"
