#!/usr/bin/python3
"""Checks one report as headless Chromium drew it.

Usage: check_report.py DOM.html SCREENSHOT.png [--hot-side right|left|none]

DOM.html (--dump-dom): the page's status element says "ok" (no script error, failed resource or
rejected promise) and gives each view's canvas rectangle. SCREENSHOT.png (same window size): each
view's canvas holds the drawn object (not only background), and the heat map's hot pixels (red to
yellow) lie on the expected side of the object as seen from the default camera (+z; x to the
right)."""
import html
import json
import re
import sys

import numpy as np

from png import read_png

BACKGROUND = np.array([244, 246, 248])  # the views' clear colour (report_template.html)
MIN_DRAWN = 0.01      # share of a view's pixels that must differ from the background
MIN_SHIFT = 0.10      # hot centroid's offset from the object's centroid, in object widths
MIN_ON_SIDE = 0.80    # share of the hot pixels on the expected half of the object


def fail(message):
    print('check_report: FAIL: ' + message)
    sys.exit(1)


def status(dom_path):
    dom = open(dom_path, encoding='utf-8').read()
    m = re.search(r'<div id="qm3d-status"[^>]*?data-views="([^"]*)"[^>]*>([^<]*)</div>', dom)
    if not m:
        fail('%s: no qm3d-status element with view rectangles (page did not finish)' % dom_path)
    text = html.unescape(m.group(2)).strip()
    if text != 'ok':
        fail('%s: page status is %r' % (dom_path, text))
    return json.loads(html.unescape(m.group(1)))


def main():
    dom_path, shot_path = sys.argv[1], sys.argv[2]
    side = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == '--hot-side' else 'none'
    rects = status(dom_path)
    image = read_png(shot_path).astype(int)
    for name in ('ref', 'dist', 'heat'):
        if name not in rects:
            fail('view %s missing from the status' % name)
        x, y, w, h = rects[name]
        if w < 50 or h < 50 or y + h > image.shape[0] or x + w > image.shape[1]:
            fail('view %s at %s is not inside the %dx%d screenshot'
                 % (name, rects[name], image.shape[1], image.shape[0]))
        view = image[y + 2:y + h - 2, x + 2:x + w - 2]
        drawn = np.abs(view - BACKGROUND).sum(axis=2) > 30
        share = drawn.mean()
        print('check_report: view %-4s %4dx%-4d drawn %.1f %%' % (name, w, h, 100 * share))
        if share < MIN_DRAWN:
            fail('view %s is (almost) only background: %.2f %% drawn' % (name, 100 * share))
        if name == 'heat' and side != 'none':
            check_hot_side(view, drawn, side)
    print('check_report: ok')


def check_hot_side(view, drawn, side):
    r, g, b = view[:, :, 0], view[:, :, 1], view[:, :, 2]
    hot = drawn & (r > 150) & (b < 90) & (r >= g)  # red, orange, yellow (the top of the map)
    ys, xs = np.nonzero(drawn)
    hy, hx = np.nonzero(hot)
    if len(hx) < 50:
        fail('the heat map has only %d hot pixels' % len(hx))
    left, right = xs.min(), xs.max()
    centre, width = (left + right) / 2, right - left + 1
    shift = (hx.mean() - centre) / width
    on_side = np.mean(hx > centre) if side == 'right' else np.mean(hx < centre)
    print('check_report: %d hot pixels, centroid %+.2f object widths from its centre, %.0f %% on the %s'
          % (len(hx), shift, 100 * on_side, side))
    if (shift if side == 'right' else -shift) < MIN_SHIFT or on_side < MIN_ON_SIDE:
        fail('the hot colours are not on the %s half' % side)


main()
