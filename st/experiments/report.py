"""What an experiment leaves behind: CSV files, PNG plots and a Markdown summary in one directory.

rep = Report("single-axis", out_dir, "Single axis (thesis 6.1)")
rep.table("Speed error", ["command", "error %"], rows, note="…")
rep.csv("speed.csv", ["t", "v"], samples)
fig, ax = rep.figure()            # a matplotlib figure, saved by rep.save_figure(fig, "speed.png")
rep.write()                       # summary.md: the tables, the notes, links to the files
"""

from __future__ import annotations

import csv
from pathlib import Path


class Report:
    def __init__(self, name: str, out_dir, title: str):
        self.name = name
        self.dir = Path(out_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.title = title
        self.parts: list = []
        self.files: list = []

    def text(self, markdown: str) -> None:
        self.parts.append(markdown.strip() + "\n")

    def table(self, title: str, headers: list, rows: list, note: str = "") -> None:
        lines = [f"### {title}", "", "| " + " | ".join(str(h) for h in headers) + " |", "|" + "---|" * len(headers)]
        lines += ["| " + " | ".join(_fmt(v) for v in r) + " |" for r in rows]
        if note:
            lines += ["", note.strip()]
        self.parts.append("\n".join(lines) + "\n")

    def csv(self, filename: str, headers: list, rows) -> Path:
        path = self.dir / filename
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(headers)
            for r in rows:
                w.writerow([_fmt(v) if isinstance(v, float) else v for v in r])
        self.files.append(path)
        return path

    def figure(self, rows: int = 1, cols: int = 1, size=(9, 5)):
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            return None, None
        fig, axes = plt.subplots(rows, cols, figsize=size, squeeze=False)
        return fig, axes

    def save_figure(self, fig, filename: str) -> Path | None:
        if fig is None:
            return None
        import matplotlib.pyplot as plt

        path = self.dir / filename
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        self.files.append(path)
        return path

    def write(self) -> Path:
        path = self.dir / "summary.md"
        body = [f"# {self.title}", ""] + self.parts
        if self.files:
            body += ["### Files", ""] + [f"- [{p.name}]({p.name})" for p in self.files]
        path.write_text("\n".join(body) + "\n")
        return path


def _fmt(v) -> str:
    if isinstance(v, float):
        if v != v:
            return "–"
        a = abs(v)
        if a == 0 or 0.01 <= a < 1e6:
            return f"{v:.4g}" if a < 1000 else f"{v:,.1f}"
        return f"{v:.3e}"
    return str(v)
