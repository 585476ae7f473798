"""Rows of text as aligned columns: the layout of every table the commands' text views
print (processes, topics, loggers, parameters)."""

from __future__ import annotations


def table(rows: list[list[str]]) -> list[str]:
    """Rows as columns of text, as wide as their widest cell."""
    if not rows:
        return []
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows]
