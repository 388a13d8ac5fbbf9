"""
Cattaneo–Mindlin: two cylinders pressed, then sheared
=====================================================

Two identical plane-strain steel cylinders (R = 10 mm, E = 210 GPa, ν = 0.3) are pressed
together by P to a contact half-width a ≈ 0.03 R, then pulled sideways by Q < μP (Coulomb,
μ = 0.3), the shear reached by moving the caps sideways, each shear an increment from the
pressed state (``previous=``). Cattaneo and Mindlin's closed forms (Johnson, *Contact
Mechanics*, §7.1), which hold exactly for identical bodies (Dundurs' β = 0): the stick zone
−c < x < c with c/a = √(1 − Q/(μP)), and the friction traction

    q(x) = μp₀ [√(1 − x²/a²) − (c/a) √(1 − x²/c²)]   for −c < x < c,   μp(x) outside it,

p₀ = 2P/(πa). The model is ``contactqp.friction.cattaneo`` (scikit-fem, 28 340 dofs, the lower
body the mirror image of the upper, each pair of surface nodes one contact); the chart shows
each pair's friction force over its length of surface against the closed form.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

import contactqp
from contactqp.friction.cattaneo import cattaneo_cylinders

R, E, NU, MU = 10.0, 210e3, 0.3, 0.3
cylinders = cattaneo_cylinders(R, E, NU, zone=1.25 * 0.03 * R, fine=0.03 * R / 25,
                               growth=0.1)
x = cylinders.x
edges = np.concatenate([x[:1], 0.5 * (x[1:] + x[:-1]), x[-1:]])
tributary = np.diff(edges)  # each pair's length of surface
problem = contactqp.Problem(**cylinders.arrays, mu=MU,
                            prescribed_values=cylinders.cap_values(0.0377, 0.0))
pressed = contactqp.solve(problem)
print(f"{problem.n} dofs, {problem.m} pairs; pressed: {pressed.message}")

figure, axes = plt.subplots(figsize=(7.5, 4.2))
sheared = []
for shift, colour in zip((0.00345, 0.00877, 0.01434), ("tab:blue", "tab:orange", "tab:green")):
    step = problem.with_values(prescribed_values=cylinders.cap_values(0.0377, shift))
    result = contactqp.solve(step, previous=pressed)
    sheared.append(result)
    P, Q = result.contact_force.sum(), result.friction_force.sum()
    a = math.sqrt(4.0 * P * R * (1.0 - NU**2) / (math.pi * E))
    p0 = 2.0 * P / (math.pi * a)
    ratio = math.sqrt(1.0 - Q / (MU * P))
    sticking = x[result.state == "stick"]  # the zone's edges: midway to the first slipping
    right = 0.5 * (sticking.max() + x[x > sticking.max()].min())
    left = 0.5 * (sticking.min() + x[x < sticking.min()].max())
    c = 0.5 * (right - left)
    print(f"Q/(μP) = {Q / (MU * P):.3f}: c/a = {c / a:.4f} from the sticking pairs, "
          f"√(1 − Q/(μP)) = {ratio:.4f}; verified: {result.verified}")
    fine = np.linspace(-a, a, 801)
    closed = MU * p0 * (np.sqrt(np.clip(1.0 - (fine / a) ** 2, 0.0, None))
                        - ratio * np.sqrt(np.clip(1.0 - (fine / (ratio * a)) ** 2, 0.0, None)))
    axes.plot(fine / a, closed / (MU * p0), color=colour, linewidth=1.0,
              label=f"Cattaneo, Q/(μP) = {Q / (MU * P):.2f}")
    axes.plot(x / a, result.friction_force[:, 0] / tributary / (MU * p0), "o", color=colour,
              markersize=3, label="contactqp (each pair's force / its length)")
axes.set_xlim(-1.3, 1.3)
axes.set_ylim(-0.5, 1.0)
axes.set_xlabel("x / a")
axes.set_ylabel("friction traction q / (μ p₀)")
axes.set_title("Cattaneo–Mindlin, two identical cylinders")
axes.legend(fontsize=7, loc="lower center", ncol=2)
figure.tight_layout()
