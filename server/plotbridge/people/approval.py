"""Which uploads wait for an operator's approval (the setting `approval`)."""

from __future__ import annotations

from plotbridge.access import Role

MODES = ("submitters", "all", "none")  # whose uploads wait; the default is the first


def needs_approval(mode: str, role: Role) -> bool:
    """`submitters`: a submitter's upload waits; `all`: every upload (an exhibition);
    `none`: no upload waits."""
    if mode == "all":
        return True
    return mode == "submitters" and role <= Role.submitter
