"""How large a figure's smallest text is where a reader sees it."""

import numpy as np

#: Where a reader sees the figures: a docs page's content column, 885 px at a 1280 px window
#: in headless Chromium (800 px taken, for narrower windows), and report.html on a
#: 1920 x 1080 screen (its column 72em = 1152 px wide; an image at most 92 % of the
#: window's height, about 900 px). Text smaller than 9 px there cannot be read.
SHOWN = {"docs page": (800, None), "report on a 1920 x 1080 screen": (1152, 900)}
SMALLEST_PX = 9.0


def smallest_text_pt(fig) -> tuple[float, str]:
    """The smallest font size (pt) of any visible, non-empty text of ``fig``, and the text."""
    from matplotlib.text import Text

    fig.draw_without_rendering()  # tick labels get their text when the figure is drawn
    return min(
        (t.get_fontsize(), t.get_text())
        for t in fig.findobj(Text)
        if t.get_visible() and t.get_text().strip()
    )


def unreadable(name: str, fig, dpi: float, where=SHOWN) -> list[str]:
    """Where ``fig``, saved at ``dpi``, shows text under :data:`SMALLEST_PX`: one line each."""
    width_px, height_px = (v * dpi for v in fig.get_size_inches())
    points, text = smallest_text_pt(fig)
    found = []
    for place, (column, screen) in where.items():
        scale = min(1.0, column / width_px, (screen or np.inf) / height_px)
        px = points / 72 * dpi * scale
        if px < SMALLEST_PX:
            found.append(f"{name} in the {place}: {text!r} at {px:.1f} px")
    return found
