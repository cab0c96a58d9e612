"""Where the lab's house B lies: ``shared/data/mapir_house_B`` beside the repository, or beside a folder above it
(a worktree of the repository sits deeper than its main checkout). Never copied into the project."""

from __future__ import annotations

from pathlib import Path

_REPO = Path(__file__).resolve().parents[2]


def house_b_folder() -> Path:
    """The first ``<ancestor>/shared/data/mapir_house_B`` above the repository (the one beside it when none is)."""
    for up in [_REPO.parent, *_REPO.parent.parents]:
        folder = up / "shared" / "data" / "mapir_house_B"
        if folder.is_dir():
            return folder
    return _REPO.parent / "shared" / "data" / "mapir_house_B"
