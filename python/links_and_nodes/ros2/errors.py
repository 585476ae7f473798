"""The one error of the ROS 2 mapping: an md that has no ROS 2 topic type, or CDR bytes that
are not a sample of the md (with the byte offset and the field)."""

from __future__ import annotations


class CdrError(ValueError):
    """An md without a ROS 2 topic mapping, or bad CDR bytes: the message names the md, the
    field and, for bytes, the offset in the CDR buffer (encapsulation header included)."""
