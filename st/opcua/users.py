"""The OPC UA server's users: a text file of `name:role:password hash` lines.

Roles: `read` (browse, read, subscribe), `operate` (and write the variables the symbol
configuration makes writable), `engineer` (and the PLC's Start, Stop and Reset). Passwords are
kept as scrypt hashes (`scrypt$n$r$p$salt$hash`, base64), never as text; `st opcua user FILE
NAME --role ROLE` adds or replaces a user.
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import os
import re

ROLES = ("read", "operate", "engineer")
_NAME = re.compile(r"^[A-Za-z0-9_.@-]{1,64}$")
_N, _R, _P = 2**14, 8, 1


class UsersError(ValueError):
    """A users file that cannot be used (the message names the file and the line)."""


def hash_password(password: str) -> str:
    salt = os.urandom(16)
    h = hashlib.scrypt(password.encode(), salt=salt, n=_N, r=_R, p=_P, dklen=32)
    return f"scrypt${_N}${_R}${_P}${base64.b64encode(salt).decode()}${base64.b64encode(h).decode()}"


def verify_password(password: str, stored: str) -> bool:
    try:
        kind, n, r, p, salt, h = stored.split("$")
        if kind != "scrypt":
            return False
        got = hashlib.scrypt(
            password.encode(), salt=base64.b64decode(salt), n=int(n), r=int(r), p=int(p), dklen=len(base64.b64decode(h))
        )
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(got, base64.b64decode(h))


def load_users(path: str) -> dict[str, tuple[str, str]]:
    """{name: (role, password hash)}."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise UsersError(f"error: {path}: cannot read the OPC UA users: {e.strerror}") from None
    out: dict[str, tuple[str, str]] = {}
    for k, line in enumerate(lines, 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        parts = text.split(":", 2)
        if len(parts) != 3 or not _NAME.match(parts[0]) or parts[1] not in ROLES or not parts[2].startswith("scrypt$"):
            raise UsersError(
                f"error: {path}:{k}: expected NAME:ROLE:HASH with a role of {', '.join(ROLES)} "
                "(st opcua user writes these lines)"
            )
        out[parts[0]] = (parts[1], parts[2])
    return out


def add_user(path: str, name: str, role: str, password: str) -> None:
    """Add `name` to the users file (made if missing), or replace its role and password."""
    if not _NAME.match(name):
        raise UsersError(f"error: user name {name!r}: letters, digits and _.@- only, at most 64")
    if role not in ROLES:
        raise UsersError(f"error: role {role!r}: one of {', '.join(ROLES)}")
    users = load_users(path) if os.path.exists(path) else {}
    users[name] = (role, hash_password(password))
    text = "# st OPC UA users: NAME:ROLE:scrypt hash (st opcua user FILE NAME --role ROLE)\n"
    text += "".join(f"{n}:{r}:{h}\n" for n, (r, h) in users.items())
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)
