"""HTML building blocks: numbers with thousands separators and units, sortable
tables, the page's style and its few lines of script (table sorting, the
full-size image viewer with its reference/test swap, figure variants). No
network: everything is inline."""
import html
import math


def esc(s):
    return html.escape(str(s))


def fmt_num(v, digits=3, unit=""):
    """1234567 -> '1,234,567'; 0.012345 -> '0.0123'; None -> ''. `digits`
    significant digits below 1000, whole numbers with separators above."""
    if v is None:
        return ""
    if isinstance(v, float) and not math.isfinite(v):
        return ""
    a = abs(v)
    if a >= 1000 or (float(v).is_integer() and a >= 1):
        text = f"{v:,.0f}"
    elif a == 0:
        text = "0"
    elif a < 1e-3:
        text = f"{v:.{digits}g}"  # 2.23e-08, not a row of zeros
    else:
        decimals = max(0, digits - 1 - int(math.floor(math.log10(a))))
        text = f"{v:,.{decimals}f}"
    return f"{text} {unit}".rstrip() if unit else text


def fmt_pct(share, digits=1):
    return "" if share is None else f"{100.0 * share:.{digits}f} %"


def cell(sort_value, text=None, cls=""):
    """A table cell that sorts by sort_value (a number or a string)."""
    if text is None:
        text = esc(sort_value) if not isinstance(sort_value, (int, float)) else fmt_num(sort_value)
    v = "" if sort_value is None else (repr(float(sort_value)) if isinstance(sort_value, (int, float))
                                       and not isinstance(sort_value, bool) else esc(sort_value))
    c = f' class="{cls}"' if cls else ""
    return f'<td data-v="{v}"{c}>{text}</td>'


def table(headers, rows, cls="sortable", caption=None):
    """headers: column titles (units in them); rows: lists of cell() strings.
    Wrapped in a scroller, so a wide table never widens the page."""
    out = [f'<div class="scroll"><table class="{cls}">']
    if caption:
        out.append(f"<caption>{caption}</caption>")
    out.append("<thead><tr>" + "".join(f'<th title="click to sort">{esc(h)}</th>' for h in headers) + "</tr></thead><tbody>")
    for r in rows:
        out.append("<tr>" + "".join(r) + "</tr>")
    out.append("</tbody></table></div>")
    return "\n".join(out)


CSS = """
body{font-family:sans-serif;margin:16px 24px;color:#222;max-width:1880px}
h1{font-size:22px}h2{font-size:19px;margin-top:28px;border-bottom:2px solid #ccd}h3{font-size:16px;margin-top:20px}
p,li{font-size:14px;line-height:1.4}
.note{color:#555;font-size:13px}
.scroll{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:13px;margin:8px 0}
td,th{border:1px solid #ccc;padding:3px 7px;text-align:right;white-space:nowrap}
th{background:#eef;cursor:pointer;position:relative}
th:first-child{text-align:left}
th[aria-sort=ascending]::after{content:" \\25B2"}th[aria-sort=descending]::after{content:" \\25BC"}
td.t{text-align:left}
caption{text-align:left;font-size:13px;color:#444;padding:2px 0}
img.plot{max-width:100%;height:auto;display:block;margin:6px 0}
.ok{color:#070}.failed{color:#b00}.notrun{color:#777}
pre{white-space:pre-wrap;font-size:12px;background:#f6f6f6;padding:4px}
.toc a{margin-right:12px}
.grid{display:grid;gap:8px 10px;align-items:start;margin:8px 0}
.grid .rowhead{font-size:13px;font-weight:bold;align-self:center;overflow-wrap:anywhere}
.grid .colhead{font-size:13px;font-weight:bold;text-align:center}
.grid figure{margin:0;min-width:0}
.grid img{display:block;width:100%;height:auto;image-rendering:pixelated;border:1px solid #999;box-sizing:border-box}
.grid img.diff,.grid img.flipmap{margin-top:3px}
.grid figcaption{font-size:12px;line-height:1.3;overflow-wrap:anywhere}
.grid a.full{display:block;cursor:zoom-in}
.colourbar{max-width:420px;width:100%;height:auto;display:block}
.toggle button{font-size:13px;margin-right:4px}.toggle button.on{font-weight:bold;background:#dde}
.shade{background:linear-gradient(to right,#f8c9a8 var(--s),transparent var(--s))}
#viewer{position:fixed;inset:0;background:rgba(20,20,20,.92);color:#eee;z-index:10;overflow:auto;padding:10px}
#viewer[hidden]{display:none}
#viewer .bar{font-size:14px;margin-bottom:6px}#viewer .bar button{margin-left:4px}
#viewer img{image-rendering:pixelated;cursor:pointer;max-width:none;border:1px solid #666}
#viewer a{color:#9cf}
"""

SCRIPT = """
<script>
(function () {
  // Sortable tables: a click on a header sorts by the cells' data-v (numbers
  // numerically, text alphabetically; empty cells last); a second click reverses.
  document.querySelectorAll('table.sortable').forEach(function (t) {
    var heads = t.tHead.rows[0].cells;
    Array.prototype.forEach.call(heads, function (th, col) {
      th.addEventListener('click', function () {
        var asc = th.getAttribute('aria-sort') !== 'ascending';
        Array.prototype.forEach.call(heads, function (h) { h.removeAttribute('aria-sort'); });
        th.setAttribute('aria-sort', asc ? 'ascending' : 'descending');
        var body = t.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        rows.sort(function (a, b) {
          var x = a.cells[col].getAttribute('data-v') || '', y = b.cells[col].getAttribute('data-v') || '';
          if (x === '' || y === '') return (x === '') - (y === '');
          var nx = Number(x), ny = Number(y);
          var c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : x.localeCompare(y);
          return asc ? c : -c;
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
  });
  // Figure variants (the same plot against RMSE or FLIP): one shown at a time.
  document.querySelectorAll('.toggle').forEach(function (tg) {
    var group = document.querySelectorAll('[data-group="' + tg.getAttribute('data-for') + '"]');
    tg.querySelectorAll('button').forEach(function (b) {
      b.addEventListener('click', function () {
        tg.querySelectorAll('button').forEach(function (o) { o.classList.toggle('on', o === b); });
        group.forEach(function (el) { el.hidden = el.getAttribute('data-variant') !== b.getAttribute('data-show'); });
      });
    });
  });
  // The full-size viewer: a thumbnail opens its image at 1:1; a click on it swaps
  // image and reference; the buttons show the |difference| x4 and the FLIP map.
  var refs = JSON.parse(document.getElementById('references').textContent || '{}');
  var v = document.getElementById('viewer'), img = document.getElementById('viewer-img');
  var title = document.getElementById('viewer-title'), open = document.getElementById('viewer-open');
  var cur = null, showing = 'image';
  // A figure's sources: its data-* attribute (a file beside the page), else the
  // image embedded in it (frames small enough are embedded at full size).
  function source(what) {
    if (what === 'reference') return refs[cur.getAttribute('data-scene')];
    var s = cur.getAttribute('data-' + what);
    return s ? s : cur.querySelector('img.image').src;
  }
  function show(what) {
    showing = what;
    img.src = source(what);
    if (what === 'reference') open.removeAttribute('href'); else open.href = cur.getAttribute('data-file-' + what);
    title.textContent = (what === 'reference' ? 'reference (abuffer)' : cur.getAttribute('data-title') +
      (what === 'image' ? '' : what === 'diff' ? ': |difference| x4' : ': FLIP error')) +
      ' - click the image to swap image and reference';
  }
  img.addEventListener('error', function () {
    title.textContent = 'not found beside this page: ' + img.getAttribute('src') + ' (open the page in its sweep folder)';
  });
  document.querySelectorAll('a.full').forEach(function (a) {
    a.addEventListener('click', function (e) {
      if (e.ctrlKey || e.metaKey || e.shiftKey || e.button !== 0) return;
      e.preventDefault();
      cur = a.closest('figure');
      show(a.getAttribute('data-kind'));
      v.hidden = false;
    });
  });
  img.addEventListener('click', function () { show(showing === 'reference' ? 'image' : 'reference'); });
  v.querySelectorAll('button[data-show]').forEach(function (b) {
    b.addEventListener('click', function () { show(b.getAttribute('data-show')); });
  });
  document.getElementById('viewer-close').addEventListener('click', function () { v.hidden = true; });
  document.addEventListener('keydown', function (e) { if (e.key === 'Escape') v.hidden = true; });
})();
</script>
"""

VIEWER = """
<div id="viewer" hidden><div class="bar"><span id="viewer-title"></span>
<button data-show="image">image</button><button data-show="reference">reference</button>
<button data-show="diff">|difference| x4</button><button data-show="flip">FLIP</button>
<a id="viewer-open" target="_blank">open this file</a> <button id="viewer-close">close (Esc)</button></div>
<img id="viewer-img" alt="full-size image"></div>
"""


def page(title, body, references_json):
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>{esc(title)}</title><style>{CSS}</style></head><body>\n" + body + VIEWER +
            f'<script type="application/json" id="references">{references_json}</script>' + SCRIPT +
            "</body></html>\n")
