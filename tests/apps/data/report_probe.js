// Injected by tests/apps/test_report_browser.cpp into a copy of a report page:
// measures the page as laid out by Chromium and writes the findings, as JSON,
// into <pre id="probe-result"> for --dump-dom. The report itself carries no
// test code.
window.addEventListener('load', function () {
  var r = {};
  var de = document.documentElement;
  r.innerWidth = window.innerWidth;
  r.scrollWidth = de.scrollWidth;

  // Every image decoded.
  var imgs = document.querySelectorAll('img'), broken = [];
  for (var i = 0; i < imgs.length; i++)
    if (!(imgs[i].complete && imgs[i].naturalWidth > 0) && imgs[i].id !== 'viewer-img') broken.push(imgs[i].alt);
  r.images = imgs.length - 1;  // not the viewer's (empty until opened)
  r.broken = broken;

  // Image grids: in each cell the difference (and FLIP map) starts at the
  // image's left edge, below it, and ends within it; no cell leaves the window.
  var cells = 0, misaligned = [], outside = [];
  document.querySelectorAll('.grid figure').forEach(function (f) {
    var a = f.querySelector('img.image'), d = f.querySelector('img.diff'), m = f.querySelector('img.flipmap');
    if (!a || !d) return;
    cells++;
    var ra = a.getBoundingClientRect(), rd = d.getBoundingClientRect();
    if (Math.abs(ra.left - rd.left) > 1 || rd.top < ra.bottom - 0.5 || rd.right > ra.right + 1)
      misaligned.push(a.alt + ': image ' + [ra.left, ra.top, ra.right, ra.bottom] + ' diff ' + [rd.left, rd.top, rd.right]);
    if (m) {
      var rm = m.getBoundingClientRect();
      if (Math.abs(rm.top - rd.top) > 1 || rm.right > ra.right + 1) misaligned.push(a.alt + ': FLIP map misplaced');
    }
    if (ra.right > window.innerWidth + 0.5 || ra.left < 0) outside.push(a.alt);
  });
  r.grid_cells = cells;
  r.misaligned = misaligned;
  r.outside = outside;

  // The points table sorts on a click on its FLIP column (ascending, then
  // descending; empty cells last both times).
  var t = document.querySelector('#points ~ p ~ .scroll table, #points + p + .scroll table');
  r.sort = 'no points table';
  if (t) {
    var heads = t.tHead.rows[0].cells, col = -1;
    for (var h = 0; h < heads.length; h++) if (heads[h].textContent === 'FLIP mean') col = h;
    if (col < 0) { r.sort = 'no FLIP mean column'; } else {
      var values = function () {
        return Array.prototype.map.call(t.tBodies[0].rows, function (row) { return row.cells[col].getAttribute('data-v'); });
      };
      var ordered = function (vals, asc) {
        var seenEmpty = false;
        for (var j = 0; j < vals.length; j++) {
          if (vals[j] === '') { seenEmpty = true; continue; }
          if (seenEmpty) return false;
          if (j > 0 && vals[j - 1] !== '' && (asc ? Number(vals[j - 1]) > Number(vals[j]) : Number(vals[j - 1]) < Number(vals[j]))) return false;
        }
        return true;
      };
      var before = values();
      heads[col].click();
      var asc = values();
      heads[col].click();
      var desc = values();
      var numbers = asc.filter(function (v) { return v !== ''; }).length;
      r.sort = (ordered(asc, true) && ordered(desc, false) && numbers >= 2 &&
                JSON.stringify(asc) !== JSON.stringify(desc)) ? 'ok' :
               'not sorted: before ' + before + ' asc ' + asc + ' desc ' + desc;
      r.sorted_rows = asc.length;
    }
  }

  // Every plot names both axes of every panel it draws.
  var plots = document.querySelectorAll('img.plot'), unlabelled = [];
  plots.forEach(function (p) {
    var axes = JSON.parse(p.getAttribute('data-axes') || '[]');
    if (!axes.length) unlabelled.push(p.alt + ': no axes recorded');
    axes.forEach(function (a, k) { if (!a[0] || !a[1]) unlabelled.push(p.alt + ' panel ' + k + ': ' + JSON.stringify(a)); });
  });
  r.plots = plots.length;
  r.unlabelled = unlabelled;

  // The viewer: a click on a thumbnail opens its image at full size, a click on
  // that swaps to the scene's reference and back.
  r.viewer = 'no thumbnail';
  var thumb = document.querySelector('a.full[data-kind="image"]');
  if (thumb) {
    var fig = thumb.closest('figure'), view = document.getElementById('viewer'), vimg = document.getElementById('viewer-img');
    var refs = JSON.parse(document.getElementById('references').textContent);
    var want = fig.getAttribute('data-image') || fig.querySelector('img.image').getAttribute('src');
    thumb.click();
    var opened = !view.hidden && vimg.getAttribute('src') === want;
    vimg.click();
    var swapped = vimg.getAttribute('src') === refs[fig.getAttribute('data-scene')];
    vimg.click();
    var back = vimg.getAttribute('src') === want;
    document.getElementById('viewer-close').click();
    r.viewer = opened && swapped && back && view.hidden ? 'ok' :
      'opened ' + opened + ', swapped to the reference ' + swapped + ', back ' + back + ', closed ' + view.hidden;
  }

  var pre = document.createElement('pre');
  pre.id = 'probe-result';
  pre.textContent = JSON.stringify(r);
  document.body.appendChild(pre);
  if (window.location.hash === '#probe-scroll-points') document.getElementById('points').scrollIntoView();
});
