"""The PLC's message log: what the program reports (ADSLOGSTR and its kin), with the PLC time.

One log per PLC, kept across online changes; `st run` prints new entries as they come."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

KINDS = ((0x04, "error"), (0x02, "warning"), (0x01, "hint"))


@dataclass(frozen=True)
class LogMessage:
    time: int  # the PLC clock, ns
    mask: int  # the caller's control mask (ADSLOG_MSGTYPE_*)
    text: str

    @property
    def kind(self) -> str:
        """error, warning, hint or log, from the mask's message type bits."""
        return next((name for bit, name in KINDS if self.mask & bit), "log")


class MessageLog:
    """The last `limit` messages and how many there were in all (`since` finds the new ones)."""

    def __init__(self, limit: int = 10000):
        self.entries: deque[LogMessage] = deque(maxlen=limit)
        self.total = 0

    def add(self, time: int, mask: int, text: str) -> None:
        self.entries.append(LogMessage(time, mask, text))
        self.total += 1

    def since(self, count: int) -> list[LogMessage]:
        """The messages added after the first `count` (as many as are still kept)."""
        new = self.total - count
        return list(self.entries)[-new:] if new > 0 else []

    def texts(self) -> list[str]:
        return [m.text for m in self.entries]
