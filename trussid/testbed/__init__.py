"""The thesis testbed as an application of :mod:`trussid.fem`: model, walls, labels, plant.

- :mod:`.model` - :func:`build_testbed` (a :class:`trussid.geometry.Testbed` to an FE
  model and the map of what is what);
- :mod:`.walls` - the wall-thickness basis and sweeps, and the model's eigen solution;
- :mod:`.perturbed` - the perturbed truths a controller is graded on;
- :mod:`.labels` - each mode named by where its energy sits;
- :mod:`.sensitivity` - analytic frequency sensitivities to each strut's wall;
- :mod:`.chain` - the lab's electronics (amplifier, filters), from its
  :class:`trussid.geometry.lab.LabSpec`;
- :mod:`.plant` - :func:`testbed_plant`, D/A volts in, accelerometer volts out;
- :mod:`.render` - the testbed's solids riding on its FE nodes.

Uses :mod:`trussid.fem` and :mod:`trussid.geometry`; names load on first use.
"""

from trussid._util.lazy import lazy_exports

_LAZY = {
    "TestbedMap": "model", "TestbedModel": "model", "build_testbed": "model",
    "solve_testbed_modes": "walls", "WallBasis": "walls", "wall_basis": "walls",
    "wall_matrices": "walls", "wall_modes": "walls", "design_at_walls": "walls",
    "ModeLabels": "labels", "label_testbed_modes": "labels",
    "wall_sensitivities": "sensitivity", "testbed_sensitivities": "sensitivity",
    "LabChain": "chain", "lab_plant": "chain",
    "TestbedPlant": "plant", "testbed_plant": "plant", "plant_summary": "plant",
    "node_load": "plant", "udf_wrench": "plant", "udf_motion": "plant",
    "testbed_decorations": "render",
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = list(_LAZY)
