"""Request guard: pure ASGI middleware and connection limits in front of the app.

`Guard` (middleware.py) answers every request's cheap questions before the app
reads a byte of its body: is the Host ours, is the client authenticated, is the
body within its route's bound, does a cookie-authenticated change come from our
own page. See docs/INTERNALS.md, "Hardening".
"""
