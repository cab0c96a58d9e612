"""
The library on your own arrays
==============================

A semantic map's class beliefs p(o_c | z_c) and an olfactory estimate p(s | g), both made up here, turned into the
semantic term p(s | z) (eq. (20)), the fused posterior p(s | g, z) (eq.
(11)) and the information gain I(S; O_n) of observing each cell (Sec. "Information Gain
Optimization").
"""

import matplotlib.pyplot as plt
import numpy as np

from psgsl_pgm import Ontology, fuse, semantic_information_gain, semantic_source_probability

ontology = Ontology.from_dict({
    "classes": ["oven", "microwave", "refrigerator", "countertop"],  # "other" is appended
    "gases": {"smoke": {"oven": 0.4, "microwave": 0.25, "refrigerator": 0.3, "countertop": 0.05}},
})
rng = np.random.default_rng(0)
class_probs = rng.dirichlet(np.full(5, 0.3), size=(40, 50))  # p(o_c | z_c), (H, W, k): fairly confident beliefs
rows, cols = np.mgrid[0:40, 0:50]
olfactory = np.exp(-((rows - 25) ** 2 + (cols - 30) ** 2) / (2 * 8.0 ** 2))  # a blob of gas evidence p(s | g)
olfactory /= olfactory.sum()

likelihood = ontology.source_likelihood("smoke")
semantic = semantic_source_probability(class_probs, likelihood, ontology.class_prior)
posterior = fuse(olfactory, semantic)
gain = semantic_information_gain(class_probs, likelihood, ontology.class_prior, olfactory=olfactory)
print(f"posterior sums to {posterior.sum():.12f}; most likely cell {np.unravel_index(posterior.argmax(), posterior.shape)}")
print(f"information gain: {gain.min():.2e} … {gain.max():.2e} nats per cell")

# %%
# The four maps side by side; each has its own colour bar (they are different quantities).
fig, axes = plt.subplots(1, 4, figsize=(13, 3.2), layout="constrained")
panels = [(olfactory, "olfactory p(s | g)"), (semantic, "semantic p(s | z)"),
          (posterior, "fused p(s | g, z)"), (gain, "I(S; O_n), nats")]
for ax, (image, title) in zip(axes, panels):
    shown = ax.imshow(image, origin="lower", cmap="viridis")
    ax.set(title=title, xlabel="column (cell)", ylabel="row (cell)")
    fig.colorbar(shown, ax=ax, shrink=0.8, label="probability" if "p(" in title else "nats")
plt.show()
