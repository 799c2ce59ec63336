#!/usr/bin/env bash
# Render the office compliance example's HTML report in a headless browser
# and save a screenshot: the documented check that the report renders.
#
#   scripts/report_screenshot.sh [OUT_DIR]          # default: report_check/
#
# Runs `lumest grid` and `lumest illuminance ... --report` on data/office.toml
# (the README's compliance example), then Chromium (Debian: `apt-get install
# chromium`; or `chromium-headless-shell`) in headless mode prints the page to
# OUT_DIR/report.png. Fails when no browser is found, the report is not
# written, or the screenshot is missing or empty. Look at the PNG: the
# figures tables with their verdicts and one isolux plot per grid must show.
# The test suite (tests/report.rs) parses the same report with an HTML5
# parser and checks its contents; this script checks that a browser draws it.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-report_check}
mkdir -p "$OUT"
LUMEST=${LUMEST:-target/release/lumest}
[ -x "$LUMEST" ] || cargo build --release --quiet
BROWSER=""
for b in chromium chromium-headless-shell chromium-browser google-chrome; do
    if command -v "$b" >/dev/null 2>&1; then BROWSER=$b; break; fi
done
[ -n "$BROWSER" ] || { echo "no headless browser found (apt-get install -y chromium)" >&2; exit 1; }
"$LUMEST" grid --scene data/office.toml --out "$OUT/office_grids.csv"
"$LUMEST" illuminance --scene data/office.toml --points "$OUT/office_grids.csv" \
    --out "$OUT/E.csv" --figures-out "$OUT/figures.csv" --time 40 \
    --report "$OUT/report.html" --isolux-dir "$OUT"
[ -s "$OUT/report.html" ] || { echo "no report written" >&2; exit 1; }
rm -f "$OUT/report.png"
"$BROWSER" --headless --no-sandbox --disable-gpu --hide-scrollbars \
    --window-size=1100,4200 --screenshot="$OUT/report.png" \
    "file://$(realpath "$OUT/report.html")" 2>/dev/null || true
[ -s "$OUT/report.png" ] || { echo "$BROWSER wrote no screenshot" >&2; exit 1; }
echo "report: $OUT/report.html; screenshot: $OUT/report.png"
