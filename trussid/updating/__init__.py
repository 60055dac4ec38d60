"""FE model updating: the six strut wall thicknesses (and modal damping) from identified modes.

Composition layer over :mod:`trussid.fem` (the testbed model, its wall basis and analytic wall
sensitivities), :mod:`trussid.geometry` (the testbed parameters) and :mod:`trussid.plid` (the grey-box
least-squares machinery and the identified models)::

    measured modes (f, zeta, shapes at sensors)  ---pairing--->  model modes at walls t
    residual r_i = (f_model,pair(i)(t) - f_i) / sigma_i ,  Jacobian d f / d t  (fem.sensitivity)
    plid.greybox.fit_parameters(r, walls, bounds, jac)  ->  walls, intervals, identifiability

Which modes carry wall information
----------------------------------
A strut's first bending pair (two planes, nearly equal frequencies) depends almost only on
that strut's wall (``d ln f / d ln t`` about 0.14 to 0.31), so the 12 bending modes fix the
six walls *as a set*: geometrically the six struts are equivalent, and swapping two walls
leaves the bending frequencies nearly unchanged. Which wall belongs to which strut is told by
(a) mode shapes (a sensor on each strut: MAC pairing), or (b) the UDF rigid-body modes,
which depend on the struts' axial stiffness with a different weight per strut. With
frequencies alone, include the UDF modes; the global search below then finds the assignment.

Pairing measured to model modes
-------------------------------
The bending modes lie close together and reorder when walls change, so pairing is redone at
every evaluation of the residual (a linear assignment, :func:`trussid.plid.modal.pair_modes`), by frequency
distance and, when identified shapes at known sensors are given, by MAC. Before fitting,
measured modes that no model mode can reach are dropped: model mode ``j`` may move by about
``|df_j/dt| * prior_range * t`` (sensitivity-aware gate) within the prior wall range.

Two stages (why: an eigen-solution of the full 372-DOF model costs ~0.1-0.4 s, too much for
a global search):

1. *Global*, on a Ritz-reduced model (the lowest modes at the nominal walls and at all walls
   scaled by 0.85 and 1.15 as a basis, carried
   as a :class:`trussid.testbed.walls.WallBasis` (:meth:`WallBasis.projected`) so that :func:`trussid.testbed.walls.wall_modes` and
   :func:`trussid.testbed.sensitivity.eigenvalue_sensitivities` apply unchanged; frequency error about
   3e-7 relative for walls within +-15 %): :func:`trussid.plid.greybox.fit_parameters` with its
   seeded multi-start over the prior box ``nominal * (1 +- prior_range)``, then pairwise
   wall exchanges as further starts (:func:`trussid.updating.fit.global_fit`): each arrangement of walls over
   the equivalent struts is its own local minimum. Exchanges that fit as well as the best
   are reported (the modes do not tell those struts apart).
2. *Local*, on the full model, from the stage-1 estimate, within the physical bounds: the
   estimate, the identifiability analysis and the intervals.

Intervals
---------
With measured-frequency standard deviations ``frequency_std_hz`` (from PLID's parameter
covariance or the scatter over sub-records, :func:`modes_from_data`), the residuals are in units
of sigma, and the walls' covariance is ``(J^T J)^-1`` in ``ln t`` (known-sigma, normal
quantile), inflated by the Birge ratio ``sqrt(chi2 / dof)`` when the fit is worse than the
stated sigmas explain. Without them, residuals are relative frequency errors and the
intervals are :mod:`trussid.plid.greybox`'s (from the residual scatter).

Measured on the bending test below (16000 samples, 40 dB): PLID's covariance gives
frequency sigmas of about 1e-4 Hz, yet each identified pole sits about 0.005 Hz from the
model mode it is paired with, because it blends the strut's two bending planes (0.05-0.1 Hz
apart, inside the 0.25 Hz half-power bandwidth). The statistical sigma alone would give
intervals that miss; the unresolved-mode term (``unresolved_sigma``, about 0.03-0.06 Hz
here; 0.14 Hz where two struts' bending pairs overlap) is what makes them honest, at the
price of 95 % wall intervals of about +-0.4 % to +-9 %.

Damping: the model's damping is one modal ratio (``Testbed.damping.modal_ratio``); it does
not depend on the walls, so its estimate is the (inverse-variance weighted) mean of the
paired modes' identified damping ratios, with a t-interval from their scatter or, when
larger, from the stated standard deviations (for a mode blended with unresolved
neighbours, these include ``span / (2 f sqrt 3)``: a blend looks more damped).

Which experiment
----------------
The lab plant (extension drive, UDF accelerometers) hardly sees the strut bending modes.
:func:`trussid.testbed.plant.testbed_plant` with ``arrangement="bending", sensors="struts"``
is the test suited to updating: all wafers driven in
anti-phase (bending) from one channel, a lateral sensor on each strut; a SIMO PLID model of
its data gives one strong mode per strut, with a shape that names the strut.

The package, in the order the work runs:

- :mod:`.identified`: modes (frequency, damping, shape, uncertainty) of an identified model
  or a record (:func:`modes_of_model`, :func:`modes_from_data`);
- :mod:`.reduction`: the Ritz-reduced wall basis and the model's modes at given walls;
- :mod:`.fit`: pairing, residual and Jacobian (:class:`~trussid.updating.fit.WallPairing`),
  the global search, intervals of walls and damping;
- :mod:`.walls`: :func:`update_walls`, the two stages end to end;
- :mod:`.results`: :class:`IdentifiedModes`, :class:`UpdateReport`; :mod:`.errors`:
  :class:`UpdateError`.
"""

from trussid.updating.errors import UpdateError
from trussid.updating.fit import WALL_NAMES
from trussid.updating.identified import modes_from_data, modes_of_model
from trussid.updating.reduction import reduced_wall_basis
from trussid.updating.results import IdentifiedModes, UpdateReport
from trussid.updating.walls import update_walls

__all__ = [
    "UpdateError",
    "IdentifiedModes",
    "UpdateReport",
    "reduced_wall_basis",
    "modes_of_model",
    "modes_from_data",
    "update_walls",
    "WALL_NAMES",
]
