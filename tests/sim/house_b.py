"""Where the lab's house B lies: ``shared/data/mapir_house_B`` beside the repository, or beside a folder above it
(a worktree of the repository sits deeper than its main checkout). Never copied into the project."""

from __future__ import annotations

from pathlib import Path

_REPO = Path(__file__).resolve().parents[2]


def shared_data(name: str) -> Path:
    """The first ``<ancestor>/shared/data/<name>`` above the repository (the one beside it when none is)."""
    for up in [_REPO.parent, *_REPO.parent.parents]:
        folder = up / "shared" / "data" / name
        if folder.is_dir():
            return folder
    return _REPO.parent / "shared" / "data" / name


def house_b_folder() -> Path:
    """The lab's house B: :func:`shared_data` ``("mapir_house_B")``."""
    return shared_data("mapir_house_B")
