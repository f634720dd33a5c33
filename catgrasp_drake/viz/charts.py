"""Bar chart of an evaluation's Table I (PNG, drawn with Pillow; no plotting library needed)."""

from __future__ import annotations

import io
import os

from PIL import Image, ImageDraw, ImageFont

from catgrasp_drake.core.fileio import atomic_write_bytes

CELLS = (("grasp", "full"), ("grasp", "single"), ("functional", "full"), ("functional", "single"))
COLORS = ((120, 170, 230), (40, 100, 190), (250, 175, 90), (215, 100, 20))


def table_chart(category: str, rows: dict, path: str | os.PathLike, *, width: int = 900, height: int = 420) -> None:
    """Grouped bars: one group per row (e.g. "paper", methods), four bars (grasp/functional x full/single view).

    ``rows``: ``{name: {"grasp": {"full": (successes, trials), ...}, "functional": {...}}}``; success rates in %.
    """
    img = Image.new("RGB", (width, height), "white")
    d = ImageDraw.Draw(img)
    font = ImageFont.load_default()
    left, right, top, bottom = 50, 20, 40, 70
    plot_h = height - top - bottom
    d.text((left, 10), f"{category}: success rate (%) per method, leave-two-out", fill="black", font=font)
    for pct in range(0, 101, 25):
        y = top + plot_h * (1 - pct / 100)
        d.line([(left, y), (width - right, y)], fill=(225, 225, 225))
        d.text((5, y - 6), f"{pct:3d}", fill="black", font=font)
    names = list(rows)
    group_w = (width - left - right) / max(len(names), 1)
    bar_w = group_w * 0.8 / len(CELLS)
    for g, name in enumerate(names):
        x0 = left + g * group_w + group_w * 0.1
        for b, (kind, view) in enumerate(CELLS):
            s, n = rows[name].get(kind, {}).get(view, (0, 0))
            if not n:
                continue
            h = plot_h * s / n
            x = x0 + b * bar_w
            d.rectangle([x, top + plot_h - h, x + bar_w - 2, top + plot_h], fill=COLORS[b])
            d.text((x, top + plot_h - h - 12), f"{100 * s / n:.0f}", fill="black", font=font)
        d.text((x0, top + plot_h + 6), name, fill="black", font=font)
    for b, (kind, view) in enumerate(CELLS):
        x = left + b * 200
        d.rectangle([x, height - 25, x + 12, height - 13], fill=COLORS[b])
        d.text((x + 16, height - 26), f"{kind}, {view} view", fill="black", font=font)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    atomic_write_bytes(path, buf.getvalue())
