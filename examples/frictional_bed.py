"""
A bar on a frictional bed
=========================

A 1 m steel bar of 1 cm² lies on a bed that resists sliding up to τ = 40 kN/m; held at its
far end, it is pulled by F = 24 kN at node 0. The bed holds it back over the slip zone
x < x_s = F/τ = 0.6 m, where the friction is at its limit, and beyond x_s nothing moves: the
closed form is u(x) = −τ(x_s − x)²/(2EA) there, exact at the nodes when one falls at x_s.
The scene is solved with friction (Tresca per node, τ times its tributary length); the chart
shows the friction force along the bar, the stick zone shaded.
"""

import numpy as np

import contactqp
from contactqp import plot

E, A, L, N, TAU, F = 2e11, 1e-4, 1.0, 40, 4e4, 24e3
bar = contactqp.Bar.uniform(A, E, length=L, elements=N)
scene = contactqp.Scene(bar, (contactqp.Support(N),), (contactqp.Load(0, -F),),
                        beds=(contactqp.Bed(TAU),), name="bar on a bed")
result = contactqp.solve(scene)
x = np.linspace(0.0, L, N + 1)
exact = -TAU * np.clip(F / TAU - x, 0.0, None) ** 2 / (2.0 * E * A)
print(result.summary())
print(f"largest |u − closed form|: {np.abs(result.u - exact).max():.2e} m "
      f"(of a pull-out of {abs(exact[0]):.3e} m)")
print(f"slipping nodes: {np.sum(result.state == 'slip')} (x < x_s = {F / TAU} m: "
      f"{np.sum(x < F / TAU)})")

# %%
chart = plot.plot_traction(result, position=x)
