"""From before people: the token's login sessions kept in DATA_DIR/sessions.json (their
digests and expiry times) move into the store once, as the token's sessions."""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

from plotbridge.people.store import TOKEN_OWNER, PeopleStore

log = logging.getLogger("plotbridge.people")


def take_old_sessions(path: Path, store: PeopleStore) -> None:
    try:
        kept = json.loads(path.read_text())
    except FileNotFoundError:
        return
    except (OSError, ValueError):
        kept = {}  # unreadable: everyone logs in again
    now = time.time()
    if isinstance(kept, dict):
        for hashed, expires in kept.items():
            if isinstance(hashed, str) and isinstance(expires, (int, float)) and expires > now:
                store.add_session(hashed, TOKEN_OWNER, "token", float(expires))
    path.unlink(missing_ok=True)
    log.info("the token's %d login sessions moved into the store", len(kept))
