"""Rows of text as aligned columns: the layout of every table the commands' text views
print (processes, topics, loggers, parameters); sizes in binary units."""

from __future__ import annotations


def size_text(n: float) -> str:
    """Bytes in binary units: `512.0 MiB`."""
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GiB"


def table(rows: list[list[str]]) -> list[str]:
    """Rows as columns of text, as wide as their widest cell."""
    if not rows:
        return []
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows]
