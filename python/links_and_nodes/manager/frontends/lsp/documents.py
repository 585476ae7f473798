"""Which open documents are configurations and which are message definitions: by the
editor's language id, else by the file name (`*.lnc`, `*.lnc.in`; md files have no
suffix)."""

from __future__ import annotations

import os

LNC = "lnc"
MD = "lnmd"


def kind_of(path: str, language_id: str | None) -> str | None:
    if language_id in (LNC, MD):
        return language_id
    name = os.path.basename(path)
    if name.endswith((".lnc", ".lnc.in")):
        return LNC
    if "." not in name:
        return MD
    return None
