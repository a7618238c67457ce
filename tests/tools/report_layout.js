// report_layout.js - appended to a `crowdbake report --html` page by tests/cli/test_report.c and run
// by headless Chromium (--dump-dom): checks the laid-out boxes, not the markup. Writes one
// line per failure and a last line, LAYOUT then OK or FAILED and the number of checks, into a
// pre element with the id layout-check that it appends to the body.
//
// Checks: no two pieces of text overlap (text boxes from DOM ranges, so a cell's padding does
// not count); nothing sticks out of the page or out of its bar track; numbers and labels never
// wrap (one line box per text node; column titles and notes may wrap between words); every bar is visible; each
// bar ends where the axis's own tick marks say its share of the budget lies on a log scale
// (from the bytes the page states, within 2 px); bars over the budget cross the budget line.
(function () {
  const failures = [];
  let checks = 0;
  const fail = (msg) => failures.push(msg);
  const check = (ok, msg) => { ++checks; if (!ok) fail(msg); };
  const describe = (node) => {
    const el = node.nodeType === 1 ? node : node.parentElement;
    const text = (node.textContent || '').trim().slice(0, 40);
    return `${el.tagName.toLowerCase()}${el.className ? '.' + String(el.className).replace(/ /g, '.') : ''} "${text}"`;
  };
  const pageWidth = document.documentElement.clientWidth;

  // Every non-blank text node with its line boxes.
  const texts = [];
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  for (let n = walker.nextNode(); n; n = walker.nextNode()) {
    if (!n.textContent.trim() || n.parentElement.closest('#layout-check, script, style, title')) continue;
    const range = document.createRange();
    range.selectNodeContents(n);
    const rects = Array.from(range.getClientRects()).filter((r) => r.width > 0 && r.height > 0);
    if (rects.length) texts.push({ node: n, rects });
  }

  // Text inside a horizontally scrolled table is laid out past the viewport on purpose; it
  // must stay inside its scroll box instead.
  const clipBox = (node) => {
    const s = node.parentElement.closest('.scroll');
    return s ? { left: s.getBoundingClientRect().left, right: s.getBoundingClientRect().left + s.scrollWidth } : { left: 0, right: pageWidth };
  };

  for (const t of texts) {
    const box = clipBox(t.node);
    for (const r of t.rects) check(r.left >= box.left - 0.5 && r.right <= box.right + 0.5, `outside the page: ${describe(t.node)}`);
    const wraps = !t.node.parentElement.closest('#types td:last-child, th, p, li, h1, h2, .legend, .overrun, .summary');
    if (wraps) check(t.rects.length === 1, `wraps onto ${t.rects.length} lines: ${describe(t.node)}`);
  }

  // No two text boxes overlap (1 px of antialiasing allowed).
  const all = [];
  for (const t of texts) for (const r of t.rects) all.push({ node: t.node, r });
  for (let i = 0; i < all.length; ++i)
    for (let j = i + 1; j < all.length; ++j) {
      const a = all[i].r, b = all[j].r;
      const w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
      const h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
      ++checks;
      if (w > 1 && h > 1) fail(`overlap: ${describe(all[i].node)} and ${describe(all[j].node)}`);
    }

  // Bars: visible, labels inside their track, and placed on the log scale the ticks show.
  const ticks = Array.from(document.querySelectorAll('.axis .tick')).map((t) => {
    const r = t.getBoundingClientRect();
    const x = t.classList.contains('first') ? r.left : t.classList.contains('last') ? r.right : (r.left + r.right) / 2;
    return { x, text: t.textContent };
  });
  check(ticks.length >= 3, `only ${ticks.length} axis ticks`);
  const shares = ticks.length && ticks[0].text.endsWith('%');
  const budget = Number(document.body.dataset.budgetBytes || 0);
  const decade = ticks.length > 1 ? ticks[1].x - ticks[0].x : 0;
  const lo = ticks.length ? Math.log10(parseFloat(ticks[0].text) / (shares ? 100 : 1)) : 0;
  for (const bar of document.querySelectorAll('.bar')) {
    const track = bar.parentElement.getBoundingClientRect(), r = bar.getBoundingClientRect();
    const bytes = Number(bar.dataset.bytes);
    const what = `${bar.dataset.kind} bar of ${bar.dataset.type}`;
    check(r.width >= 2 && r.height >= 8, `${what} is ${r.width.toFixed(1)} x ${r.height.toFixed(1)} px`);
    const label = bar.parentElement.querySelector('.value').getBoundingClientRect();
    check(label.left >= track.left - 0.5 && label.right <= track.right + 0.5, `${what}: its label sticks out of the track`);
    if (shares && budget > 0 && bytes > 0) {
      const want = ticks[0].x + (Math.log10(bytes / budget) - lo) * decade;
      if (want >= ticks[0].x) check(Math.abs(r.right - want) <= 2, `${what}: ends at ${r.right.toFixed(1)} px, its share says ${want.toFixed(1)}`);
      const line = bar.parentElement.querySelector('.budget-line');
      check(line !== null, `${what}: no budget line`);
      if (line && bytes > budget * 1.05) check(r.right > line.getBoundingClientRect().right, `${what} is over budget but ends before the line`);
      if (line && bytes < budget * 0.95) check(r.right < line.getBoundingClientRect().left, `${what} is within budget but crosses the line`);
    }
  }
  // Evenly spaced decades: a log axis.
  for (let i = 2; i < ticks.length; ++i)
    check(Math.abs(ticks[i].x - ticks[i - 1].x - decade) <= 1.5, `tick ${ticks[i].text} is not a decade from ${ticks[i - 1].text}`);

  const out = document.createElement('pre');
  out.id = 'layout-check';
  out.textContent = failures.map((f) => 'FAIL ' + f).join('\n') + `\nLAYOUT ${failures.length ? 'FAILED' : 'OK'} ${checks}\n`;
  document.body.appendChild(out);
})();
