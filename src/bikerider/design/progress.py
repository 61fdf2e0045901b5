"""The sweep's progress bar: :class:`bikerider.progress.Progress` (shared with the gap diagnosis)."""

from __future__ import annotations

from bikerider.progress import Progress

__all__ = ["Progress"]
