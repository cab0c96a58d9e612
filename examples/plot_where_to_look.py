"""
Where to look next: φ_O over camera poses
=========================================

The information gain I(S; O_n) says how much observing cell n's object would tell about the source
(Sec. "Information Gain Optimization"); a camera at pose p sees the cells of its field of view F_p, and
φ_O(p) = Σ_{n ∈ F_p} I(S; O_n) scores the pose. Here: a two-room map with a wall and a door, class beliefs that
are still uncertain in one room, and the best of eight headings at every free cell.
"""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap

from psgsl_pgm import field_of_view, kitchen_ontology, semantic_information_gain, view_information_gain

ont = kitchen_ontology()
k = len(ont.classes)
H, W = 30, 40
occupancy = np.zeros((H, W), bool)
occupancy[[0, -1], :] = occupancy[:, [0, -1]] = True  # outer walls
occupancy[:, 20] = True                               # a wall between two rooms ...
occupancy[12:17, 20] = False                          # ... with a door
rng = np.random.default_rng(1)
class_probs = np.tile(np.eye(k)[ont.classes.index("other")] * 0.9 + 0.1 / k, (H, W, 1))  # the left room: seen
class_probs[:, 21:] = rng.dirichlet(np.ones(k), size=(H, W - 21))                      # the right room: unsure
gain = semantic_information_gain(class_probs, ont.source_likelihood("smoke"), ont.class_prior)
gain[occupancy] = 0.0

camera = {"max_range": 8.0, "half_angle": np.pi / 4}             # metres and radians, on a 1-m grid here
rows, cols = np.nonzero(~occupancy)
headings = np.arange(8) * np.pi / 4
poses = np.array([(c + 0.5, r + 0.5, h) for r, c in zip(rows, cols) for h in headings])
phi = view_information_gain(gain, occupancy, poses, **camera).reshape(len(rows), len(headings))
best = np.full((H, W), np.nan)
best[rows, cols] = phi.max(axis=1)
i, j = np.unravel_index(np.nanargmax(best), best.shape)
pose = (j + 0.5, i + 0.5, headings[phi[np.flatnonzero((rows == i) & (cols == j))[0]].argmax()])
seen = field_of_view(occupancy, pose, **camera)
print(f"best pose: x = {pose[0]} m, y = {pose[1]} m, heading {np.degrees(pose[2]):.0f}°; "
      f"φ_O = {best[i, j]:.3f} nats over {seen.sum()} cells in view")

# %%
# Walls are grey. Left: I(S; O_n) per cell. Right: the best φ_O over eight headings at each free cell, and the field of view of
# the best pose (outlined). Cells behind the wall are out of view: from the left room the camera sees the right
# room only through the door.
fig, axes = plt.subplots(1, 2, figsize=(11, 3.9), layout="constrained")
shown = axes[0].imshow(np.ma.masked_where(occupancy, gain), origin="lower", cmap="viridis")
fig.colorbar(shown, ax=axes[0], label="I(S; O_n), nats")
axes[0].set(title="information gain per cell")
shown = axes[1].imshow(best, origin="lower", cmap="magma", vmin=0.0)  # from 0: the rooms compare
fig.colorbar(shown, ax=axes[1], label="max over headings of φ_O(p), nats")
axes[1].contour(seen, levels=[0.5], colors="cyan", linewidths=1.2)
axes[1].plot(j, i, "c*", markersize=12, label="best pose")
axes[1].set(title="φ_O at each free cell (best heading)")
axes[1].legend(loc="upper left", fontsize=8)
for ax in axes:
    ax.imshow(np.ma.masked_where(~occupancy, occupancy), origin="lower", cmap=ListedColormap(["0.6"]))  # walls
    ax.set(xlabel="x (cells of 1 m)", ylabel="y (cells of 1 m)")
plt.show()
