"""Retained data (VAR RETAIN / PERSISTENT) in SQLite: one atomic snapshot per commit.

The file is in WAL mode and every commit replaces the whole snapshot in one transaction, so a
process killed at any moment (kill -9) leaves the last committed snapshot whole: SQLite
either applied the transaction or rolls it back on the next open. Values are stored as JSON
(to_python form: TIME as ns, enums by name, arrays as lists, structs as objects) together
with the variable's type, and restored only into a variable of the same path and type.

A file that cannot be opened (a missing or read-only folder, a file that is not SQLite) raises
RetainError naming it. While the store is open SQLite keeps `FILE-wal` and `FILE-shm` beside it;
a clean close removes them, a killed process leaves them (the next open recovers from them).
"""

from __future__ import annotations

import json
import sqlite3
import time
from typing import Any


class RetainError(OSError):
    """The retained data file cannot be opened or used; the message names it."""


class RetainStore:
    def __init__(self, path: str):
        self.path = path
        db = None
        try:
            db = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
            db.execute("PRAGMA journal_mode=WAL")
            db.execute("PRAGMA synchronous=NORMAL")
            db.execute(
                "CREATE TABLE IF NOT EXISTS retain (path TEXT PRIMARY KEY, type TEXT NOT NULL, value TEXT NOT NULL)"
            )
            db.execute("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)")
        except sqlite3.Error as e:
            if db is not None:
                db.close()
            raise RetainError(f"cannot open the retained data file {path}: {e}") from None
        self.db = db
        self.commits = 0

    def load(self) -> dict[str, tuple[str, Any]]:
        """path → (type name, value)."""
        return {p: (t, json.loads(v)) for p, t, v in self.db.execute("SELECT path, type, value FROM retain")}

    def save(self, values: dict[str, tuple[str, Any]], plc_time: int = 0) -> None:
        """Replace the snapshot with `values` (path → (type name, value)) atomically."""
        rows = [(p, t, json.dumps(v)) for p, (t, v) in values.items()]
        db = self.db
        db.execute("BEGIN IMMEDIATE")
        try:
            db.execute("DELETE FROM retain")
            db.executemany("INSERT INTO retain VALUES (?, ?, ?)", rows)
            db.execute(
                "INSERT OR REPLACE INTO meta VALUES ('committed', ?)",
                (json.dumps({"plc_time_ns": plc_time, "wall": time.time(), "count": len(rows)}),),
            )
            db.execute("COMMIT")
        except BaseException:
            db.execute("ROLLBACK")
            raise
        self.commits += 1

    def meta(self) -> dict[str, Any]:
        row = self.db.execute("SELECT value FROM meta WHERE key = 'committed'").fetchone()
        return json.loads(row[0]) if row else {}

    def clear(self) -> None:
        self.db.execute("BEGIN IMMEDIATE")
        self.db.execute("DELETE FROM retain")
        self.db.execute("DELETE FROM meta")
        self.db.execute("COMMIT")

    def close(self) -> None:
        self.db.close()
