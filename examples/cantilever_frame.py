r"""
A frame from scratch: a cantilever against Euler-Bernoulli
==========================================================

Builds a 1 m steel cantilever of solid 20 x 10 mm rectangular section from nodes and
beam elements (:class:`trussid.fem.Model`), solves its lowest modes
(:func:`trussid.fem.solve_modes`) and its static tip deflection
(:func:`trussid.fem.solve_static`), and compares both with the closed forms of
Euler-Bernoulli beam theory:

- bending frequencies :math:`f_n = \frac{(\beta_n L)^2}{2 \pi L^2}
  \sqrt{\frac{E I}{\rho A}}` with
  :math:`\beta_n L = 1.8751, 4.6941, 7.8548, 10.9955`, in each bending plane (the
  section's two second moments of area differ by a factor of 4, so the two planes' modes
  do not coincide);
- tip deflection under a tip load :math:`P`: :math:`\delta = P L^3 / (3 E I)`.

The model uses Euler-Bernoulli elements (``beam_theory="euler-bernoulli"``) with the
consistent mass matrix, so what is left is the discretisation error of the cubic
element, which falls as the fourth power of the element length.

Run: ``python examples/cantilever_frame.py``. Imported, the module's globals hold the
results (``frequencies_hz``, ``closed_form_hz``, ``tip_deflection`` ...).
"""

import numpy as np

from trussid import fem

L = 1.0  # length [m]
N_ELEMENTS = 20
B, H = 0.020, 0.010  # section width along the element's local y, height along local z [m]
P = 10.0  # tip load [N]
steel = fem.STEEL

# %%
# The model: nodes along x, clamped at x = 0. The orientation vector spans the elements'
# local x-y plane (as NASTRAN's CBAR vector does): ``orient=[0, 0, 1]`` puts local y, and
# so the section's 20 mm width, along global z; the 10 mm height lies along global y.
model = fem.Model(beam_theory="euler-bernoulli", name="cantilever")
node_ids = np.arange(1, N_ELEMENTS + 2)
x = np.linspace(0.0, L, N_ELEMENTS + 1)
model.add_nodes(node_ids, np.column_stack([x, np.zeros_like(x), np.zeros_like(x)]))
section = fem.Section.rectangle(B, H)
model.add_beams(np.arange(1, N_ELEMENTS + 1), np.column_stack([node_ids[:-1], node_ids[1:]]),
                section, steel, orient=[0.0, 0.0, 1.0])
model.fix(node_ids[0])

modes = fem.solve_modes(model, n_modes=6)
frequencies_hz = modes.frequencies_hz

# %%
# Closed forms. Bending with displacement along global y (across the 10 mm height, the
# weak plane) uses the second moment b h^3 / 12; along global z (across the width),
# h b^3 / 12, four times more.
BETA_L = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613, 10.99554073487547])
I_weak, I_strong = B * H**3 / 12, H * B**3 / 12
mass_per_length = steel.rho * B * H


def bending_hz(second_moment):
    """Cantilever bending frequencies [Hz] for a second moment of area [m^4]."""
    return BETA_L**2 / (2 * np.pi * L**2) * np.sqrt(steel.E * second_moment / mass_per_length)


# The six lowest: four in the weak plane, two in the strong one (the weak plane's fourth,
# 280 Hz, lies below the strong plane's third, 286 Hz); axial and torsion modes lie above.
closed_form_hz = np.sort(np.concatenate([bending_hz(I_weak), bending_hz(I_strong)]))[:6]
relative_error = frequencies_hz / closed_form_hz - 1

# %%
# Static check: a tip load along global y bends the weak plane.
tip_uy = 6 * (len(node_ids) - 1) + 1  # each node's components: ux, uy, uz, rx, ry, rz
load = np.zeros(6 * len(node_ids))
load[tip_uy] = P
tip_deflection = fem.solve_static(model, load)[tip_uy]
tip_closed_form = P * L**3 / (3 * steel.E * I_weak)

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    print(f"{'mode':>4} {'FE [Hz]':>10} {'closed form [Hz]':>17} {'rel. error':>11}")
    for k, (f, f0) in enumerate(zip(frequencies_hz, closed_form_hz), 1):
        print(f"{k:>4} {f:>10.4f} {f0:>17.4f} {f / f0 - 1:>11.2e}")
    print(f"tip deflection {tip_deflection * 1e3:.6f} mm, closed form "
          f"{tip_closed_form * 1e3:.6f} mm (rel. error {tip_deflection / tip_closed_form - 1:.1e})")

    # The weak-plane mode shapes (uy along the beam) against the closed-form shapes.
    fig, ax = plt.subplots(figsize=(9, 4))
    xi = np.linspace(0, L, 200)
    for n, bl in enumerate(BETA_L):
        b = bl / L
        sigma = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
        phi = np.cosh(b * xi) - np.cos(b * xi) - sigma * (np.sinh(b * xi) - np.sin(b * xi))
        k = int(np.argmin(np.abs(frequencies_hz - bending_hz(I_weak)[n])))
        uy = modes.shapes_full[1::6, k]
        # Both normalised to 1 at the tip, where a cantilever mode is largest.
        ax.plot(xi, phi / phi[-1], color=f"C{n}", lw=1,
                label=f"closed form, {bending_hz(I_weak)[n]:.2f} Hz")
        ax.plot(x, uy / uy[-1], "o", color=f"C{n}", ms=4,
                label=f"FE mode {k + 1}, {frequencies_hz[k]:.2f} Hz")
    ax.set(xlabel="x [m]", ylabel="normalised deflection u_y",
           title="Cantilever bending modes, weak plane: FE nodes and closed form")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    plt.show()
