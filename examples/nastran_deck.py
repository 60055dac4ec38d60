r"""
A NASTRAN deck: read, solve, compare, render
============================================

Reads NASTRAN bulk data with :func:`trussid.fem.read_bdf` and solves the modes the deck
asks for (its EIGRL card) with :func:`trussid.fem.solve_modes`.

``examples/decks/cantilever_inch.bdf`` is a 40 in aluminium tube cantilever in
inch-lbf-s units: RHO is a weight density [lbf/in^3] that ``PARAM,WTMASS,0.00259`` turns
into mass, as NASTRAN decks in these units do. Its bending frequencies are known in
closed form, :math:`f_n = \frac{(\beta_n L)^2}{2 \pi L^2}
\sqrt{\frac{E I}{\mathrm{WTMASS}\,\rho A}}`, twice each (a tube bends alike in both
planes). The second value :func:`~trussid.fem.read_bdf` returns reports how the deck
was understood (mass formulation, beam theory, the eigenvalue request).

``examples/decks/frame.bdf`` (a four-legged table with a rigid top plate on an RBE2
spider, SI units) is then rendered offscreen (:func:`trussid.fem.render_mode`, OSMesa: no
display, no GPU). ``trussid modes examples/decks/frame.bdf`` prints the same frequencies.

Run: ``python examples/nastran_deck.py``. Imported, the module's globals hold the results
(``frequencies_hz``, ``closed_form_hz``, ``frame_frequencies_hz`` ...).
"""

from pathlib import Path

import numpy as np

from trussid import fem

# sphinx-gallery runs an example in its own folder, without __file__.
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
DECKS = HERE / "decks"

model, info = fem.read_bdf(DECKS / "cantilever_inch.bdf")
modes = fem.solve_modes(model, info.eigen.n_modes, autospc=info.autospc)
frequencies_hz = modes.frequencies_hz

# %%
# The closed form, from the deck's own numbers (MAT1 and PBAR cards, PARAM,WTMASS).
L = 40.0  # in
E, RHO_WEIGHT = 1.0e7, 0.0975  # psi, lbf/in^3
A, I = 0.05112942044, 0.001389761559  # in^2, in^4
BETA_L = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613])
closed_form_hz = np.repeat(
    BETA_L**2 / (2 * np.pi * L**2) * np.sqrt(E * I / (info.wtmass * RHO_WEIGHT * A)), 2)
relative_error = frequencies_hz / closed_form_hz - 1

# %%
# A 3-D frame with a rigid element and a brace.
frame, frame_info = fem.read_bdf(DECKS / "frame.bdf")
frame_modes = fem.solve_modes(frame, frame_info.eigen.n_modes, autospc=frame_info.autospc)
frame_frequencies_hz = frame_modes.frequencies_hz

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    print(f"{info.path}: {info.mass} mass ({info.mass_reason}); {info.beam_theory} "
          f"({info.beam_theory_reason}); WTMASS {info.wtmass}")
    print(f"{'mode':>4} {'trussid [Hz]':>13} {'closed form [Hz]':>17} {'rel. error':>11}")
    for k, (f, f0) in enumerate(zip(frequencies_hz, closed_form_hz), 1):
        print(f"{k:>4} {f:>13.5f} {f0:>17.5f} {f / f0 - 1:>11.2e}")
    print(f"\nframe.bdf: {np.round(frame_frequencies_hz, 2).tolist()} Hz")

    images = [fem.render_mode(frame, frame_modes, mode=k, window_size=(640, 480))
              for k in (1, 2, 3)]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4))
    for ax, img in zip(axes, images):
        ax.imshow(img)  # the renderer labels each image with its mode and frequency
        ax.set_axis_off()
    fig.tight_layout()
    plt.show()
