"""File formats: the safe YAML reader (``_yaml``), checked ``.npy`` files (``_npyfile``), atomic output folders
(``_output``), the lab's ontology tables (``_ontology_lab``), COCO class names (``_coco``), Voxeland and ``.npz``
class maps (``_class_maps``). Private: read through :meth:`psgsl_pgm.Ontology.from_yaml`, world files and
the command line.

May import: :mod:`psgsl_pgm.geometry`, :mod:`psgsl_pgm._shared`, :mod:`psgsl_pgm.kernels`.
"""

__all__: list = []
