"""The live status line of `st run` on a terminal."""

from __future__ import annotations

import io
import shutil
import sys
import time

from ..runtime.plc import PLC


class StatusLine:
    """The live status line on a terminal: state, PLC time and each task's jobs, latency, execution
    time and overruns, styled with rich. It is drawn from idle time only, at most 4 times a second
    and only when the next release is more than 1 ms away (a line costs about 0.15 ms to render)."""

    def __init__(self, plc: PLC):
        self.plc = plc
        self.tty = sys.stderr.isatty()
        self.last = 0.0
        if self.tty:  # import and warm up before the first scan, not inside one's slack
            self.text()

    def text(self):
        from rich.text import Text

        p = self.plc
        colour = {"RUN": "bold green", "STOP": "bold yellow"}.get(p.state, "bold red")
        out = Text.assemble((p.state, colour), f" t={p.time / 1e9:.1f}s")
        for t in p.tasks:
            s = t.stats
            avg = s.exec_sum / s.jobs / 1e3 if s.jobs else 0
            late = s.overruns + s.skipped
            out.append(f" | {t.name} {s.jobs} jobs, latency max {s.lat_max / 1e3:.0f} µs, exec {avg:.0f} µs, ")
            out.append(f"{late} overruns", style="red" if late else "")
        return out

    def update(self) -> None:
        now = time.monotonic()
        if not self.tty or now - self.last < 0.25 or self.plc.idle_slack < 1_000_000:
            return
        self.last = now
        from rich.console import Console

        width = shutil.get_terminal_size((120, 24)).columns or 120
        buf = io.StringIO()
        console = Console(file=buf, force_terminal=True, width=width)
        line = self.text()
        line.truncate(width - 1)
        console.print(line, end="", no_wrap=True, overflow="crop")
        sys.stderr.write("\r" + buf.getvalue() + "\x1b[K")
        sys.stderr.flush()

    def clear(self) -> None:
        if self.tty:
            sys.stderr.write("\r\n")
            sys.stderr.flush()

    def close(self) -> None:
        self.clear()
