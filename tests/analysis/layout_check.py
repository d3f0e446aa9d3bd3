"""Text layout checks of a drawn matplotlib figure, from the renderer's bounding boxes:
every piece of text inside the figure (not clipped), no two pieces of text overlapping, every
legend clear of other text and inside its axes or in no axes at all, no text smaller than
6 pt (readable at print size)."""
import matplotlib
import matplotlib.text

MIN_POINTS = 6.0
TOLERANCE = 1.0  # pixels: antialiasing and rounding of the extents


def drawn_texts(fig):
    """(description, Text, bbox) of every text the renderer draws."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    out = []
    tick_labels = set()
    for ax in fig.get_axes():
        if not ax.get_visible():
            continue
        for axis in (ax.xaxis, ax.yaxis):
            if not ax.axison:
                for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                    tick_labels.update((id(tick.label1), id(tick.label2)))
                continue
            for t in axis.get_ticklabels(minor=False) + axis.get_ticklabels(minor=True):
                tick_labels.add(id(t))
            # ticks outside the view are not drawn: only those _update_ticks keeps
            for tick in axis._update_ticks():
                for lab in (tick.label1, tick.label2):
                    if lab.get_visible() and lab.get_text():
                        out.append(("tick label '%s'" % lab.get_text(), lab,
                                    lab.get_window_extent(r)))
    for t in fig.findobj(matplotlib.text.Text):
        if id(t) in tick_labels or not t.get_visible() or not t.get_text().strip():
            continue
        if any(t is o[1] for o in out):
            continue
        # skip tick label objects of tick instances (label1/label2 not in get_ticklabels)
        if isinstance(getattr(t, "axes", None), matplotlib.axes.Axes) and \
                t in _all_tick_texts(t.axes):
            continue
        owner = t.axes
        if owner is not None and not owner.get_visible():
            continue
        out.append(("text '%s'" % t.get_text()[:40], t, t.get_window_extent(r)))
    return out


def _all_tick_texts(ax):
    s = []
    for axis in (ax.xaxis, ax.yaxis):
        for tick in axis.get_major_ticks() + axis.get_minor_ticks():
            s += [tick.label1, tick.label2]
    return s


def _overlap(a, b):
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w > TOLERANCE and h > TOLERANCE


def problems(fig, name="figure"):
    """A list of human-readable problems (empty: the layout is fine)."""
    texts = drawn_texts(fig)
    r = fig.canvas.get_renderer()
    fb = fig.bbox
    out = []
    for desc, t, b in texts:
        if b.x0 < fb.x0 - TOLERANCE or b.y0 < fb.y0 - TOLERANCE or \
                b.x1 > fb.x1 + TOLERANCE or b.y1 > fb.y1 + TOLERANCE:
            out.append("%s: %s is clipped by the figure's edge" % (name, desc))
        if t.get_fontsize() < MIN_POINTS:
            out.append("%s: %s is %.1f pt (< %g)" % (name, desc, t.get_fontsize(), MIN_POINTS))
    for i in range(len(texts)):
        for j in range(i + 1, len(texts)):
            if _overlap(texts[i][2], texts[j][2]):
                out.append("%s: %s overlaps %s" % (name, texts[i][0], texts[j][0]))
    legends = [lg for lg in fig.findobj(matplotlib.legend.Legend) if lg.get_visible()]
    for lg in legends:
        lb = lg.get_window_extent(r)
        inside = {id(t) for t in lg.get_texts()} | {id(lg.get_title())}
        for desc, t, b in texts:
            if id(t) not in inside and _overlap(lb, b):
                out.append("%s: a legend covers %s" % (name, desc))
        for ax in fig.get_axes():
            if not ax.get_visible() or not ax.axison or ax is lg.axes:
                continue
            if _overlap(lb, ax.bbox):
                out.append("%s: a legend covers part of another panel" % name)
        if lg.axes is not None and lg.axes.axison:
            ab = lg.axes.bbox
            if lb.x0 < ab.x0 - TOLERANCE or lb.x1 > ab.x1 + TOLERANCE or \
                    lb.y0 < ab.y0 - TOLERANCE or lb.y1 > ab.y1 + TOLERANCE:
                out.append("%s: a legend sticks out of its panel" % name)
    return out
