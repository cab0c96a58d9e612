"""COCO class names and the alias table that maps other spellings onto them.

The lab's ontologies (``ontology.yaml``, ``ObjectProbByRoom.yaml``) and most detectors use the 80 COCO
"things" names (``"dining table"``, ``"potted plant"``, ``"tv"``); object lists written by hand or exported
from other tools often say ``"fridge"``, ``"sofa"`` or ``"tvmonitor"`` (the Pascal VOC spelling). Names are
compared after :func:`class_key` (lower case, letters and digits only), then looked up in :data:`COCO_ALIASES`.

==================  ===================================================================
COCO name           accepted aliases (any case, spaces/underscores/hyphens ignored)
==================  ===================================================================
``airplane``        aeroplane, plane
``motorcycle``      motorbike
``couch``           sofa
``tv``              tvmonitor, television, tv monitor, monitor
``dining table``    diningtable, table
``potted plant``    pottedplant, plant, houseplant
``refrigerator``    fridge
``oven``            stove, cooker
``cell phone``      mobile phone, cellphone, phone, smartphone
``laptop``          notebook
``sink``            washbasin, basin
``toilet``          wc
``hair drier``      hair dryer
``bed``             (none)
==================  ===================================================================

Names that are neither COCO names nor aliases are kept as written (a house may have a ``countertop``).
"""

from __future__ import annotations

__all__ = ["COCO_ALIASES", "COCO_CLASSES", "canonical_class", "class_key"]

#: The 80 COCO object ("things") classes, in COCO's category order.
COCO_CLASSES: tuple[str, ...] = (
    "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat", "traffic light",
    "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat", "dog", "horse", "sheep", "cow",
    "elephant", "bear", "zebra", "giraffe", "backpack", "umbrella", "handbag", "tie", "suitcase", "frisbee",
    "skis", "snowboard", "sports ball", "kite", "baseball bat", "baseball glove", "skateboard", "surfboard",
    "tennis racket", "bottle", "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple",
    "sandwich", "orange", "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair", "couch",
    "potted plant", "bed", "dining table", "toilet", "tv", "laptop", "mouse", "remote", "keyboard",
    "cell phone", "microwave", "oven", "toaster", "sink", "refrigerator", "book", "clock", "vase", "scissors",
    "teddy bear", "hair drier", "toothbrush",
)

#: Alias -> COCO name (keys are written plainly; lookups go through :func:`class_key`).
COCO_ALIASES: dict[str, str] = {
    "aeroplane": "airplane", "plane": "airplane",
    "motorbike": "motorcycle",
    "sofa": "couch",
    "tvmonitor": "tv", "television": "tv", "tv monitor": "tv", "monitor": "tv",
    "diningtable": "dining table", "table": "dining table",
    "pottedplant": "potted plant", "plant": "potted plant", "houseplant": "potted plant",
    "fridge": "refrigerator",
    "stove": "oven", "cooker": "oven",
    "mobile phone": "cell phone", "cellphone": "cell phone", "phone": "cell phone", "smartphone": "cell phone",
    "notebook": "laptop",
    "washbasin": "sink", "basin": "sink",
    "wc": "toilet",
    "hair dryer": "hair drier",
}


def class_key(name: str) -> str:
    """Comparison key of a class name: lower case, letters and digits only (``"Dining_Table"`` -> ``"diningtable"``)."""
    return "".join(ch for ch in str(name).lower() if ch.isalnum())


_CANONICAL = {class_key(c): c for c in COCO_CLASSES}
_CANONICAL.update({class_key(a): c for a, c in COCO_ALIASES.items()})


def canonical_class(name: str) -> str:
    """The COCO spelling of a class name, or the name itself (stripped) when it is no COCO name or alias.

    Examples
    --------
    >>> canonical_class("Fridge"), canonical_class("dining_table"), canonical_class("countertop")
    ('refrigerator', 'dining table', 'countertop')
    """
    if not isinstance(name, str) or not name.strip():
        raise TypeError(f"a class name must be a non-empty string, got {name!r}")
    return _CANONICAL.get(class_key(name), name.strip())
