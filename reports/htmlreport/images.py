"""The images of a scene: a CSS grid of algorithm x k (the image, and under it
its |difference| x4 and its FLIP map), each thumbnail opening the full-size
image in the page's viewer (click to swap with the reference); the FLIP colour
bar; the depth-complexity heatmap."""
import base64
import io
import os
import subprocess
import tempfile

import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np

from . import data
from .page import esc, fmt_num
from .plots import figure_html

# Frames up to this many pixels are embedded at full size (the image's thumbnail
# is the image itself, so the viewer needs no file for it); larger ones get a
# thumbnail at most THUMB_WIDTH wide, and the viewer loads the full-size PNG
# beside the page. Difference and FLIP maps, shown at half a cell's width, are
# embedded at half resolution; the viewer opens their files.
EMBED_PIXELS = 640 * 360
THUMB_WIDTH = 640
FLIP_SCALE_ROWS = 20  # the colour scale oitsim run draws beneath the map in flip.png


def read_pfm(path):
    """HxWx3 float array, top row first."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        raw = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    ch = 3 if kind == b"PF" else 1
    img = raw[: w * h * ch].reshape(h, w, ch)
    if ch == 1:
        img = np.repeat(img, 3, axis=2)
    return np.flipud(img)


def srgb8(lin):
    c = np.clip(np.nan_to_num(lin), 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return np.floor(s * 255.0 + 0.5).astype(np.uint8)


def png_uri(rgb8):
    buf = io.BytesIO()
    plt.imsave(buf, rgb8, format="png")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def file_uri(path):
    with open(path, "rb") as f:
        return "data:image/png;base64," + base64.b64encode(f.read()).decode()


def thumbnail(rgb8):
    """Area-averaged down to at most THUMB_WIDTH wide (whole factors)."""
    h, w = rgb8.shape[:2]
    f = -(-w // THUMB_WIDTH)
    if f <= 1:
        return rgb8
    h2, w2 = h // f, w // f
    block = rgb8[: h2 * f, : w2 * f].astype(np.float32).reshape(h2, f, w2, f, -1).mean(axis=(1, 3))
    return np.round(block).astype(np.uint8)


def read_png8(path, rows=None):
    a = mpimg.imread(path)
    if a.dtype != np.uint8:
        a = np.round(a[:, :, :3] * 255.0).astype(np.uint8)
    else:
        a = a[:, :, :3]
    return a[:rows] if rows else a


class Embedder:
    """Thumbnails and viewer sources of one sweep's images."""

    def __init__(self, page_dir, width, height):
        self.page_dir = page_dir
        self.embed_full = width * height <= EMBED_PIXELS
        self.height = height

    def rel(self, path):
        return os.path.relpath(path, self.page_dir)

    def image(self, path):
        """The image's thumbnail URI: the PNG itself up to THUMB_WIDTH wide (then
        it is also the viewer's full-size image), else area-averaged down."""
        if self.embed_full:
            return file_uri(path)
        return png_uri(thumbnail(read_png8(path)))

    def half(self, path, crop_rows=None):
        """A thumbnail shown at half the cell's width (the difference and FLIP
        maps): half the thumbnail's resolution."""
        full = read_png8(path, crop_rows)
        h, w = full.shape[:2]
        f = max(1, -(-w // (THUMB_WIDTH // 2)), 2 if w > 1 and h > 1 else 1)
        h2, w2 = h // f, w // f
        small = full[: h2 * f, : w2 * f].astype(np.float32).reshape(h2, f, w2, f, -1).mean(axis=(1, 3))
        return png_uri(np.round(small).astype(np.uint8))


def colourbar_html():
    fig, ax = plt.subplots(figsize=(4.6, 0.75))
    grad = np.linspace(0, 1, 256)[None, :]
    ax.imshow(grad, aspect="auto", cmap="magma", extent=[0, 1, 0, 1])
    ax.set_yticks([])
    ax.set_xticks([0, 0.25, 0.5, 0.75, 1.0])
    ax.set_xlabel("FLIP error per pixel (0 = none, 1 = largest)")
    ax.set_ylabel(" ")
    return figure_html(fig, "FLIP colour scale", cls="colourbar")


def scene_grid(points, scene, page_dir, log):
    """The grid of one scene's images, and the scene's full-size reference URI."""
    ok = [p for p in points if os.path.exists(os.path.join(p["_dir"], "image.png"))]
    if not ok:
        return "<p>No images (no point of this scene wrote one).</p>", None
    m0 = ok[0]["metrics"]
    w, h = int(m0.get("trace.width", 0)), int(m0.get("trace.height", 0))
    emb = Embedder(page_dir, w, h)
    # One image per algorithm, image settings and k: the hardware configuration
    # changes when, never what, so every configuration's image is the same.
    cells = {}
    for p in ok:
        key = (data.algorithm(p), data.image_settings(p))
        cells.setdefault(key, {}).setdefault(data.k_of(p), p)
    ks = sorted({k for row in cells.values() for k in row if k is not None})
    ncols = max(1, len(ks))
    ref_path = os.path.join(ok[0]["_dir"], "reference.pfm")
    ref_uri = png_uri(srgb8(read_pfm(ref_path))) if os.path.exists(ref_path) else None
    out = [f'<div class="grid" style="grid-template-columns:minmax(7em,11em) repeat({ncols},minmax(0,1fr))">',
           '<div class="colhead"></div>']
    out += [f'<div class="colhead">k = {k}</div>' for k in ks] or ['<div class="colhead">image</div>']
    if ref_uri:
        out.append('<div class="rowhead">reference (abuffer, exact)</div>')
        out.append(f'<figure><img class="ref" src="{ref_uri}" alt="reference {esc(scene)}">'
                   f'<figcaption>{w} x {h}, the exact A-buffer</figcaption></figure>')
        out += ["<div></div>"] * (ncols - 1)
    for (algo, settings), row in sorted(cells.items()):
        log(f"images {scene}: {algo}")
        out.append(f'<div class="rowhead">{esc(algo)}' + (f'<br><span class="note">{esc(settings)}</span>'
                                                         if settings else "") + "</div>")
        slots = [row.get(k) for k in ks] if ks else [None]
        if None in row:  # an algorithm without k: its one image in the first column
            slots = [row[None]] + [None] * (ncols - 1)
        for p in slots:
            out.append(_cell(p, scene, emb) if p else "<div></div>")
    out.append("</div>")
    return "\n".join(out), ref_uri


def _cell(p, scene, emb):
    """A figure: the image, under it the difference and the FLIP map; each a
    link to its full-size PNG beside the page, opened in the page's viewer. The
    viewer shows the image itself when it is embedded at full size, else (and
    for the difference and FLIP maps) the file."""
    d, m = p["_dir"], p["metrics"]
    title = data.algo_label(p) + (" (k not used)" if data.k_of(p) is None else "")
    files = {kind: emb.rel(os.path.join(d, f"{kind}.png")) for kind in ("image", "diff", "flip")}
    has_flip = os.path.exists(os.path.join(d, "flip.png"))
    attrs = (f'data-scene="{esc(scene)}" data-title="{esc(title)} ({esc(p["id"])})" '
             + " ".join(f'data-file-{k}="{esc(v)}"' for k, v in files.items())
             + ("" if emb.embed_full else f' data-image="{esc(files["image"])}"')
             + f' data-diff="{esc(files["diff"])}" data-flip="{esc(files["flip"])}"')

    def link(kind, thumb, cls, alt):
        return (f'<a class="full" href="{esc(files[kind])}" data-kind="{kind}">'
                f'<img class="{cls}" src="{thumb}" alt="{esc(alt)}"></a>')

    parts = [link("image", emb.image(os.path.join(d, "image.png")), "image", f"{title}: image")]
    under = '<div style="display:grid;grid-template-columns:1fr 1fr;gap:3px">'
    under += link("diff", emb.half(os.path.join(d, "diff.png")), "diff", f"{title}: |difference| x4")
    under += (link("flip", emb.half(os.path.join(d, "flip.png"), emb.height), "flipmap", f"{title}: FLIP map")
              if has_flip else "<div></div>")
    parts.append(under + "</div>")
    cap = [f"<b>{esc(title)}</b>"]
    if data.flip_mean(m) is not None:
        cap.append(f"FLIP {fmt_num(data.flip_mean(m))}")
    if data.rmse(m) is not None:
        cap.append(f"RMSE {fmt_num(data.rmse(m))}")
    return (f"<figure {attrs}>" + "".join(parts) +
            f"<figcaption>{' &middot; '.join(cap)}</figcaption></figure>")


def depth_heatmap(trace_path, oitsim):
    """Transparent fragments per pixel (`oitsim info --heatmap`), or None."""
    if not trace_path or not os.path.exists(trace_path) or not oitsim:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        pfm = os.path.join(tmp, "depth.pfm")
        r = subprocess.run([oitsim, "info", trace_path, "--heatmap", pfm, "--json"], capture_output=True)
        if r.returncode != 0 or not os.path.exists(pfm):
            return None
        counts = read_pfm(pfm)[:, :, 0]
    fig, ax = plt.subplots(figsize=(7, 7 * counts.shape[0] / max(counts.shape[1], 1) + 0.8))
    im = ax.imshow(counts, cmap="inferno", interpolation="nearest")
    fig.colorbar(im, ax=ax, label="transparent fragments per pixel", fraction=0.046)
    covered = counts[counts > 0]
    ax.set_title(f"depth complexity: max {int(counts.max())}, mean over covered pixels "
                 f"{covered.mean() if covered.size else 0:.1f}")
    ax.set_axis_off()
    return figure_html(fig, "depth complexity")
