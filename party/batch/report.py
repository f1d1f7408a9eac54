"""What a batch tells a person: its pass rate and failure reasons, and a contact sheet of every
item's front view with its status, to look a dataset over at a glance."""

from __future__ import annotations

import math
import re
from collections import Counter
from pathlib import Path

import numpy as np

STATUS_COLOURS = {"passed": "#2e7d32", "failed": "#c62828", "error": "#6a1b9a", "timeout": "#ef6c00"}
"""Each status's colour on the contact sheet."""

THUMBNAIL = 256
"""Side of a contact sheet's tile [px]."""


def reason_kind(reason: str) -> str:
    """A reason with what differs between items (numbers, seams, panels, files) left out, to
    count reasons of one kind together: "seam a.edge[1]-b.edge[2] left open 3.1 mm by the sewing"
    -> "seam … left open # mm by the sewing", "in panel 'a' and panel 'b'" -> "in panel …"."""
    kind = re.sub(r"\bseam \S+", "seam …", reason)
    kind = re.sub(r"\bpanel '[^']*'( and panel '[^']*')*", "panel …", kind)
    kind = re.sub(r"\S*/\S*", "…", kind)
    return re.sub(r"\d+(\.\d+)?(e[-+]?\d+)?", "#", kind)


def tally(rows: list[dict]) -> tuple[Counter, Counter]:
    """(items by status, reasons of items that did not pass by :func:`reason_kind`)."""
    statuses = Counter(r["status"] for r in rows)
    reasons = Counter(reason_kind(reason) for r in rows if r["status"] != "passed" for reason in r["reasons"] or [])
    return statuses, reasons


def contact_sheet(path: Path, dataset: Path, rows: list[dict]) -> None:
    """Write ``path``: a grid of every item's ``images/front.png`` (a blank tile where it has
    none), each titled with its name and status in the status's colour."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    columns = max(1, min(8, math.ceil(math.sqrt(len(rows)))))
    lines = max(1, math.ceil(len(rows) / columns))
    fig, axes = plt.subplots(lines, columns, figsize=(2.2 * columns, 2.5 * lines), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, row in zip(axes.flat, rows):
        front = dataset / row["item"] / "images" / "front.png"
        if front.exists():
            with Image.open(front) as image:
                image.thumbnail((THUMBNAIL, THUMBNAIL))
                ax.imshow(np.asarray(image.convert("RGB")))
        else:
            ax.imshow(np.full((THUMBNAIL, THUMBNAIL, 3), 235, np.uint8))
            ax.text(THUMBNAIL / 2, THUMBNAIL / 2, "no picture", ha="center", va="center", fontsize=8, color="#777")
        colour = STATUS_COLOURS[row["status"]]
        ax.axis("on")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"{row['item']}\n{row['status']}", fontsize=6, color=colour)
        for spine in ax.spines.values():
            spine.set_visible(True)
            spine.set_edgecolor(colour)
            spine.set_linewidth(2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
