#!/usr/bin/env bash
# Browser test of `chronolux view`, run by .ci/run: starts the viewer on a free port,
# drives headless Chromium (Debian's chromium + chromium-driver, through Python selenium)
# to load the page, select the metal sphere and move it with the page's + button, and
# checks that the image changed and the page's queue counter came back to 0 for that
# edit. Saves a screenshot of the page (default docs/viewer.png).
# Usage: scripts/ci/view.sh PATH/TO/chronolux [PYTHON_VENV_DIR] [SCREENSHOT.png]
set -euo pipefail
BIN=$(readlink -f "$1")
VENV=${2:-.venv-view}
SHOT=${3:-docs/viewer.png}
WORK=$(mktemp -d /tmp/chronolux-view.XXXXXX)
log() { echo "view-test: $*"; }
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
    log "installing Debian's chromium and chromium-driver"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium chromium-driver >/dev/null
fi
if [ ! -x "$VENV/bin/python" ]; then
    if ! python3 -m venv "$VENV"; then
        rm -rf "$VENV"
        $SUDO apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends python3-venv
        python3 -m venv "$VENV"
    fi
fi
"$VENV/bin/python" -c "import selenium" 2>/dev/null || "$VENV/bin/pip" install -q --disable-pip-version-check selenium

SERVER=""
cleanup() {
    if [ -n "$SERVER" ]; then kill "$SERVER" 2>/dev/null || true; wait "$SERVER" 2>/dev/null || true; fi
    rm -rf "$WORK"
}
trap cleanup EXIT

# Port 0: the viewer takes a free port and prints its address.
"$BIN" view --port 0 --max-spp 8 --photons 30000 >"$WORK/server.out" 2>"$WORK/server.err" &
SERVER=$!
URL=""
for _ in $(seq 600); do
    URL=$(grep -o 'http://127\.0\.0\.1:[0-9]*/' "$WORK/server.out" || true)
    [ -n "$URL" ] && break
    kill -0 "$SERVER" 2>/dev/null || { cat "$WORK/server.err"; log "FAILED: the viewer exited"; exit 1; }
    sleep 0.1
done
[ -n "$URL" ] || { log "FAILED: the viewer printed no address within 60 s"; exit 1; }
log "viewer at $URL"

mkdir -p "$(dirname "$SHOT")"
"$VENV/bin/python" - "$URL" "$SHOT" <<'PY'
import hashlib, sys, time
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select

url, shot = sys.argv[1], sys.argv[2]
opts = webdriver.ChromeOptions()
opts.binary_location = "/usr/bin/chromium"
for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
          "--window-size=1120,800"):
    opts.add_argument(a)
# Debian's driver, given by path: selenium does not look for (or download) another one.
driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)

def wait(what, cond, timeout):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = cond()
        if v:
            return v
        time.sleep(0.1)
    raise SystemExit(f"view-test: FAILED: {what} within {timeout} s (status {status()})")

def status():
    return driver.execute_script("return window.viewer && window.viewer.status")

def image_hash():
    src = driver.find_element(By.ID, "view").get_attribute("src") or ""
    return hashlib.sha256(src.encode()).hexdigest()

try:
    driver.get(url)
    # Idle before the edit: nothing queued and the image at --max-spp (it stops changing).
    wait("the first image, refined to 8 spp",
         lambda: (s := status()) and s["queued"] == 0 and s["spp"] == 8, 120)
    before = image_hash()
    Select(driver.find_element(By.ID, "nodes")).select_by_visible_text("metal_sphere")
    for _ in range(4):
        driver.find_element(By.ID, "translate-x-plus").click()
    sent = wait("the edits sent", lambda: driver.execute_script("return window.viewer.sent") or 0, 30)
    seen_queue = []
    def settled():
        s = status()
        if s["edit"] >= sent and s["queued"] > 0:
            seen_queue.append(s["queued"])
        return s["edit"] >= sent and s["queued"] == 0 and s["spp"] == 8
    t0 = time.time()
    wait(f"edit {sent} applied, the queue drained to 0 and the image refined", settled, 180)
    after = image_hash()
    if after == before:
        raise SystemExit("view-test: FAILED: the image did not change after moving the sphere")
    shown = driver.find_element(By.ID, "queued").text
    if shown != "0":
        raise SystemExit(f"view-test: FAILED: the page shows {shown} queued groups")
    s = status()
    driver.save_screenshot(shot)
    print(f"view-test: image changed; queue seen at up to {max(seen_queue, default=0)} groups, "
          f"drained {s['settled_after']:.2f} s after the last edit (edit {s['edit']}); "
          f"waited {time.time() - t0:.1f} s; screenshot {shot}")
finally:
    driver.quit()
PY
kill "$SERVER" 2>/dev/null || true
wait "$SERVER" 2>/dev/null || true
SERVER=""
log "passed"
