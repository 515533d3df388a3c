"""People, API keys, sessions, approvals and the audit log (docs/INTERNALS.md, "People and
roles"). The role table itself is `plotbridge.access`."""

from plotbridge.people.access import Access, Identity
from plotbridge.people.store import PeopleStore

__all__ = ["Access", "Identity", "PeopleStore"]
