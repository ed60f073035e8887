#!/usr/bin/env python3
"""Cross-process tests of the web console (web_console) in a real browser: Debian's chromium,
headless, driven through python3-selenium and chromium-driver (docs/web_console.md).

operator: a world server (with its session log) and a haptic node with a scripted hand, a
headless graphics node and an audio guide; the console; its operator's page open in chromium.
The page shows the station with the loop rate the haptic node reports, the screen and the guide
as stations of their own, and for each the sample the session log stored (rate, overruns,
faults, deadline misses, bytes per second), which session_report's newest counts are too;
a world change with a wrong token gets 401 and the world stays; one sent from the page with
the token reaches the world server and comes back to the page as the new world.

tls: the console with --tls-cert/--tls-key: HTTPS and WSS only. A client that trusts the
certificate reads the state; a plain HTTP request to the port gets no answer; the page in
chromium goes live over WSS and shows the world.

view: the live 3-D view at / in chromium with software WebGL (SwiftShader): it draws the start
menu (every object and control, the meshes loaded from the glTF files the console exported),
and alice's five fingertip spheres and her hand's figure (where three.js has them in its scene) where
her haptic node's trace has her fingertips and hand base while her hand holds still; the board
shows the start menu's message in English, and in Japanese after the switch; the page's canvas
from a headless graphics node's camera shows the fingertips, books and buttons where the
graphics node's frame does (colour masks' centroids within 4 px), and her whole hand (its
difference mask: the page without its hands, the frame after she left) within 3 px;
HANDSHARE_WEB_SCREENSHOT=FILE saves what it drew.

view_bodies: the view of the solar system while alice lifts the ball and pushes the lever to
Mars and back (tests/data/lever_alice.hand), beside a headless graphics node: the page draws the
lever turned to Mars' detent (the scene file's angle) with Mars' board, and the lifted ball where
the graphics node draws it (its --state-out at exit, read between two looks at the page); the
page's canvas from the graphics node's camera shows her fingertips and the lever where its last
frame does.

view_book: the view of the start menu while alice opens the solar system's book
(tests/data/book_alice.hand), beside a headless graphics node: once the graphics node logs it
open at its first spread, the page draws it open with that spread's text from the scene file, in
English, and in Japanese after the switch, and the spread's picture on its left page.

view_deform: the view of the dinosaur world while alice presses the triceratops' tail and holds
(tests/data/tail_alice.hand), beside a headless graphics node: once the world server's field is
still, every vertex of the tail is drawn where the graphics node draws it (X_WO p_OV + u_W, its
--deformation-out), the page's vertex v being the world server's node v (its --dump-deformation
mesh). The page's canvas, from the graphics node's camera, against its frames: while her hand
comes down and presses, the snapshots whose stamps (her device state, the tail's revision) a
frame shows, by the fingertips' colours; held, what she changed (her hand and the dent) and
the dent alone, by difference masks against the page and a frame before she came.

visit: the questionnaire at /visit on a phone-sized chromium. A world server whose visitors'
turns last 0.05 minutes (--visit-minutes) and logs the session; alice's haptic node; her turn
ends and the board says so (the console's state, and the page). The page with a wrong token
gets 401 and a script without or with a wrong token too; the answers sent from the page with
the token reach the world server, and session_report finds them, alone, in its questionnaire
table (count, mean, sd per kind and question) and her turn in its turns.
HANDSHARE_VISIT_SCREENSHOT=FILE saves the page.

operator_tour: the operator's actions and Table 4 live. A logged world server in the start menu,
the console, then alice opening the solar system's book (tests/data/book_alice.hand). Commands
for a visitor nobody get 404; from the page: the session sent to the dinosaurs through the
solar system's arrow (a control event), then to a world no control of the current one links to
(an operator command), the tour restarted
(the start menu again, alice's turn begun afresh) and alice's turn ended (the board thanks her).
The page's Table 4 by kind of control equals session_report's on the world server's log, which
has alice's two turns.

usage: web_console_test.py operator|operator_tour|tls|view|view_bodies|view_deform|view_book|visit --bin-dir DIR --domain D --work DIR
"""
import json
import math
import os
import re
import secrets
import ssl
import subprocess
import sys
import urllib.error
import urllib.parse
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from session_test import (ASSETS, CONSOLE_POLL_S, DATA, PressWatch, check, fem_cache, held_weights, last_frame, last_trace_row,  # noqa: E402
                          read_inp_nodes, read_json, read_trace, run_cases, scene_object, settled_since, wait_until)

from selenium import webdriver  # noqa: E402  (python3-selenium, deploy/install_deps.sh)
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
# The world server's tick rate on the page (one second's ticks) against its 60 Hz: its ticks
# are due at absolute deadlines and a late one is caught up, so only a stall of more than 5
# periods (re-synced, ticks lost) or a second cut at a tick's end moves it.
TICK_RATE_TOLERANCE = 0.1
RATE_TOLERANCE = 0.05  # the page's last 1 s window against the node's whole-run mean: a sim loop at 1 kHz


def start_browser(work, extra_flags=(), window_size="1280,1400", phone=None):
    """Headless chromium under chromedriver, with a profile of its own in the work folder.
    phone=(width, height): a phone's screen in CSS pixels (chromium's device emulation: a
    headless window is never narrower than 500 px)."""
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    if phone:
        options.add_experimental_option("mobileEmulation", {"deviceMetrics": {
            "width": phone[0], "height": phone[1], "pixelRatio": 1.0, "touch": True}})
    for flag in (*extra_flags, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 f"--window-size={window_size}", f"--user-data-dir={os.path.join(work, 'chromium-profile')}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(CHROMEDRIVER, log_path=os.path.join(work, "chromedriver.log"))
    return webdriver.Chrome(service=service, options=options)


def post_json(base, path, body, token):
    """POST `body` (JSON) to `path` as a script would, with the token (None: without): (status, body text)."""
    headers = {"Content-Type": "application/json"}
    if token is not None:
        headers["Authorization"] = "Bearer " + token
    req = urllib.request.Request(base + path, data=json.dumps(body).encode(), headers=headers, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def post_world(base, world, token):
    """POST /api/world as a script would: (status, body)."""
    return post_json(base, "/api/world", {"world": world}, token)


def write_token(work):
    """A fresh operator's token in a file only its owner reads: (token, path)."""
    token = secrets.token_urlsafe(24)
    path = os.path.join(work, "token")
    with open(path, "w") as f:
        f.write(token + "\n")
    os.chmod(path, 0o600)
    return token, path


# Every row of the page's stations table: its node, user and kind (data attributes), the text of
# its kind, user and device cells, and each numeric cell by its class (rate, jitter, step,
# overruns, resyncs, faults, deadlines, sent, dropped, age). Read in one script: the page redraws
# the table with every state, so elements found in one call are gone in the next.
STATION_ROWS_JS = (
    "return Array.from(document.querySelectorAll('#stations tbody tr'), (row) => {"
    "  const r = {node: row.dataset.node, data_user: row.dataset.user};"
    "  for (const c of row.cells) r[c.classList.contains('num') ? c.classList[1] : (c.className || 'text' + c.cellIndex)] ="
    "      c.textContent;"
    "  return r;"
    "});")


def page_station(driver, user):
    """The page's row of `user`'s first station as {column: text} (device: its device), or None."""
    for r in driver.execute_script(STATION_ROWS_JS):
        if r["data_user"] == user:
            return {**r, "device": r.get("device", r.get("text1", ""))}  # text1: a page without cell classes
    return None


def page_stations(driver):
    """The page's stations by node: {node: {kind, user, device, rate, ..., age}}."""
    return {r["node"]: r for r in driver.execute_script(STATION_ROWS_JS) if r.get("node")}


# The operator page's numbers against the session log's row of the same sample: the page rounds
# the rate to 0.1 Hz and bytes per second to 1 B/s; counts are exact.
PAGE_RATE_ROUNDING_HZ = 0.05 + 1e-9
PAGE_BYTES_ROUNDING = 0.5 + 1e-9


def logged_rows(log_db, node):
    """The session log's loop statistics rows of `node`, newest first (read-only, beside the
    world server's writing: WAL)."""
    import sqlite3
    db = sqlite3.connect(f"file:{log_db}?mode=ro", uri=True, timeout=5)
    try:
        return db.execute("SELECT unix_ns, rate_hz, overruns, faults, deadline_misses, sent_bytes_per_s "
                          "FROM loop_statistics WHERE node = ? ORDER BY id DESC LIMIT 20", (node,)).fetchall()
    except sqlite3.OperationalError:
        return []  # the table is made with the log: only while the world server creates it
    finally:
        db.close()


def page_row_in_log(row, rows):
    """The log row that is the page's sample (rate, overruns, faults, deadline misses, bytes/s
    within the page's rounding), or None."""
    for unix_ns, rate, overruns, faults, deadlines, sent in rows:
        if (abs(float(row["rate"]) - rate) <= PAGE_RATE_ROUNDING_HZ and int(row["overruns"]) == overruns
                and int(row["faults"]) == faults and int(row["deadlines"]) == deadlines
                and abs(float(row["sent"]) - sent) <= PAGE_BYTES_ROUNDING):
            return unix_ns, rate, overruns, faults, deadlines, sent
    return None


def send_from_page(driver, world, token):
    """Chooses `world` on the page, types the token, presses Send; returns the status the page shows."""
    Select(driver.find_element(By.ID, "goto-world")).select_by_value(world)
    field = driver.find_element(By.ID, "goto-token")
    field.clear()
    field.send_keys(token)
    return click_and_wait(driver, element_id="goto-send")


def click_and_wait(driver, element_id=None, css=None):
    """Clicks a button of the page's actions and returns (status, text) of its answer."""
    result = driver.find_element(By.ID, "goto-result")
    driver.execute_script("arguments[0].removeAttribute('data-status'); arguments[0].textContent = '';", result)
    (driver.find_element(By.ID, element_id) if element_id else driver.find_element(By.CSS_SELECTOR, css)).click()
    status = wait_until("the page's answer", 20, lambda: result.get_attribute("data-status"))
    return int(status), result.text


def case_operator(h, domain):
    session = f"it-web-{os.getpid()}"
    token, token_file = write_token(h.work)
    log_db = os.path.join(h.work, "session.sqlite")
    h.start("world_server", "world_server", "--domain", domain, "--session", session, "--log", log_db)
    h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
            "--device", "sim", "--script", os.path.join(DATA, "alice.hand"))
    h.wait_for_line("world_server", "member joined: user=alice", 30)
    # A screen and a guide: stations of their own on the page, with their loops' numbers.
    h.start("screen", "graphics_node", "--domain", domain, "--session", session, "--name", "screen", "--headless",
            "--frames", 100000, "--fps", 2, "--out", os.path.join(h.work, "frames"))
    h.start("guide", "audio_guide", "--domain", domain, "--session", session, "--name", "guide",
            "--out", os.path.join(h.work, "speech"))
    port = start_view(h, domain, session, "--name", "operator-console", "--token-file", token_file)
    base = f"http://127.0.0.1:{port}"
    h.wait_for_line("console", "world 'start_menu' revision 1", 30)

    driver = start_browser(h.work)
    try:
        driver.get(base + "/operator")
        # The station appears with a fresh loop rate (LoopStatistics, once a second).
        row = wait_until("alice's station on the page with a fresh rate", 30,
                         lambda: (lambda r: r if r and r["rate"] and float(r["age"] or 99) < 2.5 else None)(
                             page_station(driver, "alice")),
                         lambda: driver.find_element(By.TAG_NAME, "body").text)
        page_rate = float(row["rate"])
        check(row["device"] == "sim", f"the page shows alice's device as '{row['device']}', not 'sim'")
        check(driver.find_element(By.ID, "world").text == "start_menu", "the page does not show the start menu")
        check(driver.find_element(By.ID, "tick").text == "60 Hz", "the page does not show the server's 60 Hz tick")
        check("Welcome" in driver.find_element(By.ID, "board-en").text, "the page does not show the board")

        # Every station, screen and guide and the world server's tick, fresh, as its kind; and what
        # the page shows of each is the sample the world server logged (found among its newest rows
        # of that node: the tick's own samples reach its log through its own reader).
        nodes = {"haptic_node/alice": ("station", "sim"), "graphics_node/screen": ("screen", ""),
                 "audio_guide/guide": ("guide", ""), "world_server/tick": ("world server", "")}
        rows = wait_until("alice's station, the screen, the guide and the world server's tick on the page, fresh", 60,
                          lambda: (lambda r: r if all(n in r and r[n]["rate"] and float(r[n]["age"] or 99) < 2.5
                                                      for n in nodes) else None)(page_stations(driver)),
                          lambda: driver.find_element(By.ID, "stations").text)
        for node, (kind, device) in nodes.items():
            check(rows[node]["kind"] == kind and rows[node]["device"] == device,
                  f"the page shows {node} as kind '{rows[node]['kind']}', device '{rows[node]['device']}', "
                  f"not '{kind}', '{device}'")
        def in_log(node):
            row = page_stations(driver).get(node)
            return page_row_in_log(row, logged_rows(log_db, node)) if row else None
        matched = {}
        for node in nodes:
            matched[node] = wait_until(f"the session log's row of the sample the page shows for {node}", 20,
                                       lambda: in_log(node),
                                       lambda: f"page {page_stations(driver).get(node)}, log {logged_rows(log_db, node)[:3]}")
        # Numbers that are measured, not zeros: alice sends device states (the console's 20 Hz),
        # the screen draws at most its 2 frames a second (a loaded machine's second may hold 3),
        # the guide's loop runs (a pass that speaks takes seconds: no lower bound beyond 0).
        check(matched["haptic_node/alice"][5] > 1000, f"alice sent {matched['haptic_node/alice'][5]} B/s")
        check(0.2 <= matched["graphics_node/screen"][1] <= 3, f"the screen drew {matched['graphics_node/screen'][1]} Hz")
        check(matched["audio_guide/guide"][1] > 0, f"the guide's loop ran at {matched['audio_guide/guide'][1]} Hz")
        # The world server ticks at its 60 Hz: the page's sample counts the ticks of one second.
        check(abs(matched["world_server/tick"][1] - 60.0) <= TICK_RATE_TOLERANCE * 60.0,
              f"the world server ticked at {matched['world_server/tick'][1]} Hz, not 60 Hz within "
              f"{TICK_RATE_TOLERANCE:.0%}")
        for node in nodes:
            check(matched[node][5] > 0, f"{node} sent no bytes by its statistics")

        # Wrong and missing tokens: 401, from the page and from a script; the world stays.
        status, text = send_from_page(driver, "dinosaur", "not-the-token-" + secrets.token_hex(8))
        check(status == 401, f"a wrong token from the page got {status} ({text}), not 401")
        status, body = post_world(base, "dinosaur", None)
        check(status == 401, f"no token got {status} ({body}), not 401")
        status, body = post_world(base, "dinosaur", token + "x")
        check(status == 401, f"a wrong token got {status} ({body}), not 401")
        status, body = post_world(base, "no_such_world", token)
        check(status == 404, f"an unknown world got {status} ({body}), not 404")

        # The token: the session goes to the solar system, and the page follows it.
        status, text = send_from_page(driver, "solar_system", token)
        check(status == 202, f"the world change from the page got {status} ({text}), not 202")
        h.wait_for_line("world_server", "control button_solar_system by operator-console: scene 'solar_system'", 30)
        wait_until("the page showing the solar system", 20,
                   lambda: driver.find_element(By.ID, "world").text == "solar_system")
        # ... and every node: alice's haptic node builds it, the screen draws it, the guide sounds
        # its cue.
        h.wait_for_line("alice", "scene 'solar_system' revision 2", 30)
        h.wait_for_line("screen", "scene 'solar_system' revision 2 received", 30)
        h.wait_for_line("guide", "(world: world solar_system)", 30)
        # The refused requests were never published: the console's one control event (the
        # events of one writer arrive in order, so a refused one would have come first).
        log = h.log("world_server")
        check(len(re.findall(r"control \S+ by operator-console", log)) == 1,
              "the world server applied other control events of the console than the one sent with the token")
        check("scene 'dinosaur'" not in log, "a world change without the right token reached the world server")
        wait_until("the page showing the solar system's board", 20,
                   lambda: "Moon" in driver.find_element(By.ID, "board-en").text)
        driver.execute_script("window.scrollTo(0, 0);")
        driver.save_screenshot(os.path.join(h.work, "operator.png"))
        check_page_log(driver, "the page", ignore="/api/world")
    finally:
        driver.quit()

    check(h.stop("console", 30) == 0, "web_console failed")
    summary = re.search(r"served (\d+) requests \((\d+) refused\)", h.log("console"))
    check(summary and int(summary.group(2)) >= 4, "web_console did not count the refused requests")
    check(h.stop("alice", 30) == 0, "haptic_node alice failed")
    node_rate = float(re.search(r"loop statistics: rate ([0-9.]+) Hz", h.log("alice")).group(1))
    check(abs(page_rate - node_rate) <= RATE_TOLERANCE * node_rate,
          f"the page showed alice's loop at {page_rate} Hz, the node reports {node_rate} Hz")
    check(h.stop("screen", 30) == 0, "graphics_node screen failed")
    check(h.stop("guide", 30) == 0, "audio_guide failed")
    check(h.stop("world_server", 30) == 0, "world_server failed")
    # session_report: each node's samples, and its newest sample's counts as the log has them.
    report_exe = os.path.join(h.bin_dir, "world_server", "session_report")
    csv = subprocess.run([report_exe, log_db, "--csv"], capture_output=True, text=True, timeout=60)
    check(csv.returncode == 0, f"session_report failed: {csv.stderr}")
    for node in nodes:
        newest = logged_rows(log_db, node)[0]
        samples = re.search(rf"^\d+,station,{re.escape(node)},samples,(\d+)$", csv.stdout, re.M)
        check(samples and int(samples.group(1)) >= 3, f"session_report has no samples of {node}:\n{csv.stdout}")
        for field, value in (("overruns", newest[2]), ("faults", newest[3]), ("deadline_misses", newest[4])):
            check(f",station,{node},{field},{value}\n" in csv.stdout,
                  f"session_report's {field} of {node} is not the log's newest {value}:\n{csv.stdout}")
    shown = "; ".join(f"{n}: {m[1]:.1f} Hz, {m[2]} overruns, {m[3]} faults, {m[4]} deadline misses, {m[5]:.0f} B/s"
                      for n, m in matched.items())
    print(f"operator page: alice's loop {page_rate} Hz on the page, {node_rate} Hz at the node; "
          f"wrong tokens 401; the page's world change reached the world server; the page's stations are "
          f"the session log's samples ({shown})")


def case_tls(h, domain):
    session = f"it-webtls-{os.getpid()}"
    cert, key = os.path.join(h.work, "cert.pem"), os.path.join(h.work, "key.pem")
    made = subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
                           "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
                           "-keyout", key, "-out", cert], capture_output=True, text=True, timeout=60)
    check(made.returncode == 0, f"openssl could not make a certificate: {made.stderr}")
    h.start("world_server", "world_server", "--domain", domain, "--session", session)
    h.start("console", "web_console", "--domain", domain, "--session", session, "--listen", "127.0.0.1:0",
            "--tls-cert", cert, "--tls-key", key)
    h.wait_for_line("console", "listening on https://127.0.0.1:", 30)
    port = int(re.search(r"listening on https://127\.0\.0\.1:(\d+)", h.log("console")).group(1))
    h.wait_for_line("console", "world 'start_menu' revision 1", 30)
    trusted = ssl.create_default_context(cafile=cert)
    with urllib.request.urlopen(f"https://127.0.0.1:{port}/api/state", context=trusted, timeout=10) as r:
        state = json.loads(r.read())
    check(state["world"]["scene"] == "start_menu", f"the state over HTTPS has world {state['world']}")
    check(state["console"]["actions_enabled"] is False, "actions are on without a token file")
    try:
        urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=10)
        plain = "answered"
    except (urllib.error.URLError, ConnectionError, OSError) as e:
        plain = f"refused ({e})"
    check(plain != "answered", "the TLS console answered plain HTTP")
    driver = start_browser(h.work, ("--ignore-certificate-errors",))
    try:
        driver.get(f"https://127.0.0.1:{port}/operator")
        wait_until("the page live over WSS", 30, lambda: driver.find_element(By.ID, "link").text == "live",
                   lambda: driver.find_element(By.TAG_NAME, "body").text)
        wait_until("the page showing the start menu", 20,
                   lambda: driver.find_element(By.ID, "world").text == "start_menu")
        check(not driver.find_element(By.ID, "goto-send").is_enabled(), "the page offers actions without a token")
    finally:
        driver.quit()
    check(h.stop("console", 30) == 0, "web_console failed")
    check(h.stop("world_server", 30) == 0, "world_server failed")
    print(f"tls: state over HTTPS, plain HTTP {plain}, the page live over WSS")


TIP_TOLERANCE_M = 1e-5  # the trace prints 6 significant digits (under 1 um here); 10 um is far below a fingertip
PALM_CENTER_H = [0.0, 0.0, -0.004]  # the screens' palm box in the hand base's frame (figure/hand_figure.hpp)
SIM_FINGERTIP_RADIUS_M = 0.008  # a simulated device's fingertips (haptic::DeviceCapabilities)


def case_view(h, domain):
    session = f"it-webview-{os.getpid()}"
    trace = os.path.join(h.work, "alice.csv")
    h.start("world_server", "world_server", "--domain", domain, "--session", session)
    h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
            "--device", "sim", "--script", os.path.join(DATA, "alice.hand"), "--trace", trace)
    # A screen beside the view: its frames from its camera, compared with the page's canvas from
    # the same camera at the end.
    frames = os.path.join(h.work, "frames")
    h.start("spectator", "graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--out", frames)
    port = start_view(h, domain, session)
    h.wait_for_line("console", "world 'start_menu' revision 1", 30)
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=10) as r:
        world = json.loads(r.read())["world"]
    meshes = sum(1 for o in world["view"] if o["mesh"])
    check(len(world["view"]) == 7 and meshes == 6,
          f"the start menu's view has {len(world['view'])} objects, {meshes} meshes (the table and 6 controls expected)")
    wait_until("alice's hand still at its hold pose", 60, lambda: settled_since(trace) >= 0.5, lambda: h.log("alice"))
    tips = last_trace_row(trace)
    base_row = read_trace(trace)[-1]
    driver = start_browser(h.work, SOFTWARE_WEBGL)
    try:
        driver.get(f"http://127.0.0.1:{port}/")
        state = wait_until("the view with the start menu's meshes and alice's hand", 60, lambda: (lambda v: v if v and
                           v["world"] == "start_menu" and v["meshesLoaded"] + v["meshesFailed"] == meshes and
                           "alice" in v["hands"] and v["frames"] > 5 else None)(
                               driver.execute_script("return window.handshareView || null;")),
                           lambda: str(driver.execute_script("return window.handshareView || null;")) +
                           str(driver.get_log("browser")))
        check(state["meshesFailed"] == 0, f"{state['meshesFailed']} meshes did not load: {driver.get_log('browser')}")
        shown = state["hands"]["alice"]
        check(len(shown) == 5, f"the view draws {len(shown)} of alice's fingertips, not 5")
        worst = max(abs(a - b) for p, q in zip(shown, tips) for a, b in zip(p, q))
        check(worst <= TIP_TOLERANCE_M, f"the view's fingertips are up to {worst} m from the trace's: {shown} vs {tips}")
        # Her palm where the screens' hand figure puts it: its box centred at X_WH (0, 0, -4 mm)
        # with H the trace's hand base (hx..qz), turned as H; then her fingers' links and joints.
        palm = state.get("palms", {}).get("alice")
        check(palm is not None, f"the view draws no palm for alice: {state.get('palms')}")
        q_WH = [base_row[a] for a in ("qw", "qx", "qy", "qz")]
        p_WP = [base_row[a] + b for a, b in zip(("hx", "hy", "hz"), rotate(q_WH, PALM_CENTER_H))]
        palm_off = max(abs(a - b) for a, b in zip(palm["p_W_m"], p_WP))
        check(palm_off <= TIP_TOLERANCE_M, f"the view's palm is {palm_off} m off her hand figure's: {palm} vs {p_WP}")
        palm_turn = quaternion_angle(palm["q_WB_wxyz"], q_WH)
        check(palm_turn <= ANGLE_TOLERANCE_RAD, f"the view's palm is turned {palm_turn} rad off her hand base: {palm} vs {q_WH}")
        figure = state["figures"]["alice"]
        check(len(figure["boxes"]) == 16 and len(figure["spheres"]) == 15,
              f"the view draws {len(figure['boxes'])} boxes and {len(figure['spheres'])} spheres of alice's hand, "
              f"not her palm, 15 links and 15 joints")
        # Each finger's last link ends at its fingertip sphere's surface (the figure's rule).
        link_off = 0.0
        for f, tip in enumerate(tips):
            last = figure["boxes"][1 + 3 * f + 2]
            axis = rotate(last["q_WB_wxyz"], [0.0, 1.0, 0.0])
            end = [p + 0.5 * last["size_m"][1] * a for p, a in zip(last["p_W_m"], axis)]
            link_off = max(link_off, abs(math.dist(end, tip) - SIM_FINGERTIP_RADIUS_M))
        check(link_off <= TIP_TOLERANCE_M, f"alice's last links end {link_off} m off her fingertips' surface")
        # The board: the start menu's message, in English, then in Japanese after the switch.
        with open(os.path.join(ASSETS, "scenes", "start_menu.json")) as f:
            messages = {m["language"]: m for m in json.load(f)["messages"]}
        board = wait_until("the board in English", 20, lambda: driver.execute_script("return window.handshareView.board;"))
        check(board["language"] == "en" and board["text"] == messages["en"]["text"] and
              board["next_action"] == messages["en"]["next_action"], f"the board in English: {board}")
        driver.find_element(By.CSS_SELECTOR, "#languages button[data-lang='ja']").click()
        board_ja = driver.execute_script("return window.handshareView.board;")
        check(board_ja["language"] == "ja" and board_ja["text"] == messages["ja"]["text"] and
              board_ja["next_action"] == messages["ja"]["next_action"], f"the board in Japanese: {board_ja}")
        check(driver.find_element(By.ID, "board-text").text == messages["ja"]["text"],
              "the page does not show the Japanese board")
        drawn = driver.execute_script(
            "const c = document.getElementById('view'); const g = c.getContext('webgl2') || c.getContext('webgl');"
            "return g !== null;")
        check(drawn, "the canvas has no WebGL context")
        check_page_log(driver, "the view")
        shot = os.environ.get("HANDSHARE_WEB_SCREENSHOT") or os.path.join(h.work, "view.png")
        driver.save_screenshot(shot)
        orbit = check_orbit(driver)
        pixels = compare_with_frame(h, driver, port, frames, "start_menu", meshes, FRAME_COLOURS, hand_user="alice")
    finally:
        driver.quit()
    stop_all(h, "console", "world_server")
    print(f"view: {state['objects']} objects, {state['meshesLoaded']} meshes from glTF, alice's 5 fingertips within "
          f"{worst:.1e} m of her trace and her palm within {palm_off:.1e} m, {palm_turn:.1e} rad; the board in "
          f"English and Japanese; {state['frames']} frames drawn; screenshot {shot}")
    print(f"view: against the graphics node's frame from its camera: {pixels}")
    print(f"view: a finger and the mouse turn it about the table: {orbit}")


def check_orbit(driver):
    """A visitor turns the view: a one-finger drag (touch events through the DevTools protocol's
    input, as a tablet's), then a mouse drag, each moves the camera about the table's point it
    looks at (its distance kept), never under the table's plane; the page logs no error."""
    def eye():
        o = driver.execute_script("return window.handshareView.orbit();")
        check(o is not None, "the view has no orbit controls without a camera in its URL")
        return o["eye"], o["target"]
    before, target = eye()
    driver.execute_cdp_cmd("Emulation.setTouchEmulationEnabled", {"enabled": True, "maxTouchPoints": 5})
    rect = driver.execute_script("const r = document.getElementById('view').getBoundingClientRect();"
                                 "return [r.left + r.width / 2, r.top + r.height / 2];")
    x, y = rect
    driver.execute_cdp_cmd("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": x, "y": y}]})
    for k in range(1, 11):
        driver.execute_cdp_cmd("Input.dispatchTouchEvent", {"type": "touchMove", "touchPoints": [{"x": x + 20 * k, "y": y - 6 * k}]})
    driver.execute_cdp_cmd("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    touched, target_after = eye()
    radius = math.dist(before, target)
    check(math.dist(touched, before) > 0.05 * radius, f"a finger's drag did not turn the view: {before} -> {touched}")
    check(abs(math.dist(touched, target_after) - radius) <= 1e-6 and target_after == target,
          f"a finger's drag did not turn the view about its target: {before} -> {touched} about {target_after}")
    driver.execute_cdp_cmd("Emulation.setTouchEmulationEnabled", {"enabled": False})
    ActionChains(driver).move_to_element(driver.find_element(By.ID, "view")).click_and_hold() \
        .move_by_offset(-150, 200).release().perform()
    moused, target_after = eye()
    check(math.dist(moused, touched) > 0.05 * radius, f"a mouse drag did not turn the view: {touched} -> {moused}")
    check(moused[2] > target[2], f"the view went under the table: eye {moused}, target {target}")
    check_page_log(driver, "the view while turned")
    return (f"eye {[round(v, 3) for v in before]} -> {[round(v, 3) for v in touched]} (finger) -> "
            f"{[round(v, 3) for v in moused]} (mouse), {radius:.3f} m from the table's point")


# What the page's canvas and a graphics node's frame from the same camera are compared by: the
# pixels of each colour that only these objects have (the fingertips' colours, and the books'
# and buttons' colours of the start menu, a book and its button sharing one; the blue pair is
# left out: alice's hand lies over the blue book, and what shows of it between her links and
# the screens' label over it puts its centroid 5.5 px off, measured with the links drawn on
# both; her whole hand is compared by its own mask instead), classified by
# chromaticity (r, g, b) / (r + g + b), which the two renderers' white lights leave alone, among
# bright (max >= 60 of 255) and saturated ((max - min) / max >= 0.3) pixels: the table, the palm
# and the hand's links, labels, grid and caption fall out. Each colour's mask must cover
# at least 20 pixels in both, and its centroid lie within FRAME_TOLERANCE_PX of the other's.
FINGERTIP_COLOURS = {"thumb": (1.0, 0.0, 0.0), "index": (0.0, 1.0, 0.0), "middle": (0.0, 0.0, 1.0),
                     "ring": (1.0, 1.0, 0.0), "little": (0.0, 1.0, 1.0)}
FRAME_COLOURS = {**FINGERTIP_COLOURS, "green book and button": (0.3, 0.6, 0.3), "purple book and button": (0.7, 0.4, 0.7)}
FRAME_CHROMA_DISTANCE = 0.1
FRAME_TOLERANCE_PX = 4.0  # of 640 x 480: the screens draw labels over the books, a closed book's white pages, finger links over the fingertips


def colour_masks(image, colours):
    """{colour name: set of (x, y)} of an RGB PIL image, by colours ({name: rgb})."""
    refs = {name: [c / sum(rgb) for c in rgb] for name, rgb in colours.items()}
    masks = {name: set() for name in colours}
    w, h = image.size
    data = image.load()
    for y in range(h):
        for x in range(w):
            r, g, b = data[x, y][:3]
            hi, lo = max(r, g, b), min(r, g, b)
            if hi < 60 or (hi - lo) < 0.3 * hi:
                continue
            total = float(r + g + b)
            c = (r / total, g / total, b / total)
            name, d = min(((n, math.dist(c, ref)) for n, ref in refs.items()), key=lambda t: t[1])
            if d <= FRAME_CHROMA_DISTANCE:
                masks[name].add((x, y))
    return masks


def frame_times(frames):
    """The rows of a headless graphics node's frame_times.csv: [{"frame", "file", "scene",
    "hands": {user: stamp_ns}, "objects": {id: stamp_ns}, "deformations": {id: revision}}]
    (stamp_ns as decimal strings, as the page has them)."""
    rows = []
    path = os.path.join(frames, "frame_times.csv")
    if not os.path.exists(path):
        return rows
    with open(path) as f:
        next(f, None)
        for line in f:
            if not line.endswith("\n"):
                break  # being written
            frame, file, scene, _, hands, objects, fields = line.rstrip("\n").split(",")
            split = lambda text: dict(item.split("@") for item in text.split(";") if item)
            rows.append({"frame": int(frame), "file": os.path.join(frames, os.path.basename(file)), "scene": scene,
                         "hands": split(hands), "objects": split(objects),
                         "deformations": {k: int(v) for k, v in split(fields).items()}})
    return rows


def decode_png(data_url):
    import base64
    import io
    from PIL import Image

    return Image.open(io.BytesIO(base64.b64decode(data_url.split(",", 1)[1]))).convert("RGB")


# The hands' mask: the pixels where an image with the hands differs from the same view without
# them (the page: its canvas drawn again with the hands hidden; a graphics node: its frame after
# the hand's user left, nothing else having moved), by more than this in a channel of 255. It
# holds the palm, the fingers' links and joints, and the fingertips, whatever their colour.
HAND_DIFF_THRESHOLD = 40
HAND_MASK_TOLERANCE_PX = 3.0  # centroids of 640 x 480: the two renderers' shading and edges
HAND_MASK_MIN_IOU = 0.7       # without the links the page's mask is palm and fingertips only


def difference_mask(image, background, threshold=HAND_DIFF_THRESHOLD):
    """The pixels where two images differ by more than `threshold` in a channel."""
    w, h = image.size
    a, b = image.load(), background.load()
    return {(x, y) for y in range(h) for x in range(w)
            if max(abs(a[x, y][k] - b[x, y][k]) for k in range(3)) > threshold}


def compare_masks(name, a, b, where, tolerance_px, min_iou):
    """Checks two masks of one thing (the page's, the frame's): at least 20 pixels each, their
    centroids within tolerance_px and their IoU at least min_iou. Returns (distance, IoU)."""
    check(len(a) >= 20 and len(b) >= 20, f"{name}: {len(a)} pixels on the page, {len(b)} in {where}")
    ca = [sum(p[k] for p in a) / len(a) for k in range(2)]
    cb = [sum(p[k] for p in b) / len(b) for k in range(2)]
    d, iou = math.dist(ca, cb), len(a & b) / len(a | b)
    check(d <= tolerance_px, f"{name}: the page's centroid {ca} is {d:.1f} px from the frame's {cb} ({where})")
    check(iou >= min_iou, f"{name}: the page's and the frame's masks overlap {iou:.2f} (IoU), under {min_iou} ({where})")
    return d, iou


def compare_with_frame(h, driver, port, frames, world, meshes, colours, hidden_allowed=(), ready=lambda v: True,
                       hand_user=None):
    """The page from the graphics node's camera (its camera.json in the URL) against the graphics
    node's last frame, both while alice's hand holds still (the graphics node is stopped here):
    every colour of `colours`; those of hidden_allowed may be hidden in both (under 20 pixels:
    a fingertip behind a held ball). With hand_user, also that user's whole hand (its
    difference mask: the page without its hands, the graphics node's frame after the user
    left, which this stops): the frame compared is then the last that shows the hand. Returns
    a line to print."""
    driver.get(camera_url(port, frames))
    wait_until("the view from the graphics node's camera", 60, lambda: (lambda v: v and v["world"] == world and
               v["meshesLoaded"] == meshes and "alice" in v["hands"] and v["frames"] > 5 and ready(v))(page_view(driver)),
               lambda: str(page_view(driver)) + str(driver.get_log("browser")))
    check("bad URL" not in driver.find_element(By.ID, "status").text, driver.find_element(By.ID, "status").text)
    snap = driver.execute_script("return window.handshareView.snapshot();")
    page = decode_png(snap["png"])
    page.save(os.path.join(h.work, "page_from_camera.png"))
    hand_line = ""
    if hand_user:
        # The frame: the newest that shows the hand (still since before the page was read);
        # the background: a later one without it, once the user has left.
        shown = wait_until(f"a frame with {hand_user}'s hand", 30, lambda: [r for r in frame_times(frames)
                                                                           if hand_user in r["hands"]])[-1]
        check(h.stop(hand_user, 30) == 0, f"{hand_user}'s haptic node failed")
        bare_row = wait_until(f"a frame after {hand_user} left", 30, lambda: next(
            (r for r in frame_times(frames) if r["frame"] > shown["frame"] and hand_user not in r["hands"]), None))
        check(h.stop("spectator", 20) == 0, "the spectator did not end cleanly")
        from PIL import Image
        frame_file = shown["file"]
        frame = Image.open(frame_file).convert("RGB")
        frame_bare = Image.open(bare_row["file"]).convert("RGB")
        page_mask = difference_mask(page, decode_png(snap["bare"]))
        frame_mask = difference_mask(frame, frame_bare)
        d, iou = compare_masks(f"{hand_user}'s hand", page_mask, frame_mask, f"{frame_file} against {bare_row['file']}",
                               HAND_MASK_TOLERANCE_PX, HAND_MASK_MIN_IOU)
        hand_line = (f"; {hand_user}'s whole hand (palm, links, joints, fingertips: {len(page_mask)} and "
                     f"{len(frame_mask)} px) {d:.1f} px (IoU {iou:.2f})")
    else:
        check(h.stop("spectator", 20) == 0, "the spectator did not end cleanly")
        _, frame_file, _, frame, _ = last_frame(frames)
    check(page.size == frame.size, f"the page's canvas is {page.size}, the graphics node's frame {frame.size}")
    page_masks, frame_masks = colour_masks(page, colours), colour_masks(frame, colours)
    worst, lines, compared = 0.0, [], 0
    for name in colours:
        a, b = page_masks[name], frame_masks[name]
        if name in hidden_allowed and len(a) < 20 and len(b) < 20:
            lines.append(f"{name} hidden in both")
            continue
        check(len(a) >= 20 and len(b) >= 20, f"{name}: {len(a)} pixels on the page, {len(b)} in {frame_file}")
        compared += 1
        ca = [sum(p[k] for p in a) / len(a) for k in range(2)]
        cb = [sum(p[k] for p in b) / len(b) for k in range(2)]
        d = math.dist(ca, cb)
        worst = max(worst, d)
        lines.append(f"{name} {d:.1f} px (IoU {len(a & b) / len(a | b):.2f})")
        check(d <= FRAME_TOLERANCE_PX, f"{name}: the page's centroid {ca} is {d:.1f} px from the frame's {cb} ({frame_file})")
    return f"{compared} colours' centroids within {worst:.1f} px: " + ", ".join(lines) + hand_line


SOFTWARE_WEBGL = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist")
ANGLE_TOLERANCE_RAD = 1e-4  # the trace's 6 significant digits of a unit quaternion: ~1e-6; the page's floats


def quaternion_angle(a, b):
    """The angle [rad] between two rotations given as (w, x, y, z) quaternions (q and -q alike)."""
    na = math.sqrt(sum(x * x for x in a))
    nb = math.sqrt(sum(x * x for x in b))
    d = min(1.0, abs(sum(x * y for x, y in zip(a, b))) / (na * nb))
    return 2.0 * math.acos(d)


def quaternion_multiply(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw]


def rotate(q, v):
    """v rotated by the unit quaternion q = (w, x, y, z)."""
    w, x, y, z = quaternion_multiply(quaternion_multiply(q, [0.0, *v]), [q[0], -q[1], -q[2], -q[3]])
    return [x, y, z]


def page_view(driver):
    return driver.execute_script("return window.handshareView || null;")


PROGRAM_OF = {"console": "web_console", "alice": "haptic_node alice"}


def check_page_log(driver, who, ignore=None):
    """The page logged no error (a blocked script or socket under the CSP would be one); `ignore`:
    errors about a URL a test refused on purpose (a 401 is logged as an error)."""
    errors = [e for e in driver.get_log("browser")
              if e["level"] == "SEVERE" and (ignore is None or ignore not in e["message"])]
    check(not errors, f"{who} logged errors: {errors}")


def stop_all(h, *labels):
    """Stops each process in turn (SIGTERM); each must exit 0 within 30 s."""
    for label in labels:
        check(h.stop(label, 30) == 0, f"{PROGRAM_OF.get(label, label)} failed")


def start_view(h, domain, session, *args, port_label="console"):
    """The console on a free port (`args`: more of its options), and the port once it listens."""
    h.start(port_label, "web_console", "--domain", domain, "--session", session, "--listen", "127.0.0.1:0", *args)
    h.wait_for_line(port_label, "listening on http://127.0.0.1:", 30)
    return int(re.search(r"listening on http://127\.0\.0\.1:(\d+)", h.log(port_label)).group(1))


BODY_TOLERANCE_M = 5e-4  # a held ball jiggles in the grip between two reads (about 1e-4 m); 0.5 mm is a pixel of the view here
LEVER_TOLERANCE_RAD = 1e-6  # the console's double arithmetic against this script's


def case_view_bodies(h, domain):
    session = f"it-webbodies-{os.getpid()}"
    trace = os.path.join(h.work, "alice.csv")
    state_file = os.path.join(h.work, "spectator_state.json")
    h.start("world_server", "world_server", "--domain", domain, "--session", session, "--scene", "solar_system")
    h.wait_for_line("world_server", "message board #1", 30)
    h.start("spectator", "graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--out", os.path.join(h.work, "frames"), "--state-out", state_file)
    port = start_view(h, domain, session)
    h.wait_for_line("console", "world 'solar_system' revision 1", 30)
    driver = start_browser(h.work, SOFTWARE_WEBGL)
    try:
        driver.get(f"http://127.0.0.1:{port}/")
        wait_until("the view of the solar system", 60, lambda: (lambda v: v and v["world"] == "solar_system" and
                   v["meshesLoaded"] + v["meshesFailed"] >= 1 and v["frames"] > 5)(page_view(driver)),
                   lambda: str(page_view(driver)) + str(driver.get_log("browser")))
        h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
                "--script", os.path.join(DATA, "lever_alice.hand"), "--trace", trace)
        # The lever in Mars' detent: drawn turned by the detent's angle about x of its frame, and
        # the board says Mars.
        h.wait_for_line("spectator", "control 'lever_planet' of 'solar_system' at index 1 (by alice)", 90)
        lever = wait_until("the page's lever in Mars' detent", 20, lambda: (lambda c: c if c and c["index"] == 1 and
                           not c["moving"] else None)(page_view(driver).get("controls", {}).get("lever_planet")),
                           lambda: f"the page's controls: {page_view(driver).get('controls')}")
        with open(os.path.join(ASSETS, "scenes", "solar_system.json")) as f:
            spec = [c for c in json.load(f)["controls"] if c["id"] == "lever_planet"][0]
        angle = spec["min_angle_rad"] + (spec["max_angle_rad"] - spec["min_angle_rad"]) / (spec["detents"] - 1)
        expected = quaternion_multiply(spec["orientation_wxyz"], [math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0])
        lever_off = quaternion_angle(lever["q_WO_wxyz"], expected)
        check(lever_off <= LEVER_TOLERANCE_RAD and max(abs(a - b) for a, b in zip(lever["p_WO_m"], spec["position_m"])) <= 1e-9,
              f"the page draws the lever at {lever}, not turned {angle} rad about its x at {spec['position_m']} "
              f"({lever_off} rad off)")
        check(lever["user"] == "alice" and lever["type"] == "lever", f"the lever's state: {lever}")
        wait_until("Mars' board on the page", 20, lambda: (lambda b: b if b and "Mars" in b["text"] else None)(
                   page_view(driver).get("board")), lambda: str(page_view(driver).get("board")))
        # The ball, lifted again after the lever went back, held still: where the graphics node
        # draws it (its state at exit, between two looks at the page).
        ball = scene_object("solar_system", "ball")
        wait_until("alice holding the ball twice", 120, lambda: len(held_weights(trace, 0.5 * ball["mass_kg"] * 1.62)) >= 2,
                   lambda: h.log("alice")[-2000:])
        before = page_view(driver).get("bodies", {}).get("ball")
        check_page_log(driver, "the view")
        shot = os.path.join(h.work, "view_bodies.png")
        driver.save_screenshot(shot)
        # The page again, from the graphics node's camera, against its last frame (it stops
        # here): her fingertips around the held ball (two of them behind it in both) and the
        # lever, which only this world's lever has the colour of.
        pixels = compare_with_frame(h, driver, port, os.path.join(h.work, "frames"), "solar_system", 3,
                                    {**FINGERTIP_COLOURS, "lever": (0.8, 0.6, 0.1)}, hidden_allowed=("middle", "ring"),
                                    ready=lambda v: "ball" in v.get("bodies", {}))
        after = page_view(driver).get("bodies", {}).get("ball")
        shown = read_json(state_file)
        check(shown is not None and shown["objects"]["ball"]["from"] == "object_state",
              f"the graphics node drew no object state of the ball: {shown}")
        drawn = shown["objects"]["ball"]
        check(before is not None and after is not None, f"the page drew no pose of the ball: {before}, {after}")
        lift = drawn["p_WO_m"][2] - ball["position_m"][2]
        check(lift >= 0.03, f"the ball is {lift} m above where the world began: not lifted")
        body_off = max(max(abs(a - b) for a, b in zip(look["p_WO_m"], drawn["p_WO_m"])) for look in (before, after))
        check(body_off <= BODY_TOLERANCE_M,
              f"the page draws the ball up to {body_off} m from the graphics node: {before}, {after} vs {drawn}")
        body_turn = max(quaternion_angle(look["q_WO_wxyz"], drawn["q_WO_wxyz"]) for look in (before, after))
        check(body_turn <= 0.02, f"the page's ball is turned {body_turn} rad from the graphics node's")
        check(after["owner"] == "alice", f"the page says the ball's owner is {after['owner']!r}, not alice")
    finally:
        driver.quit()
    stop_all(h, "console", "alice", "world_server")
    print(f"view_bodies: the lever in Mars' detent ({lever_off:.1e} rad off the scene file's angle), Mars' board; "
          f"the ball lifted {lift * 1e3:.1f} mm, drawn within {body_off * 1e3:.3f} mm and {body_turn:.1e} rad of the "
          f"graphics node; screenshot {shot}")
    print(f"view_bodies: against the graphics node's frame from its camera: {pixels}")


def case_view_book(h, domain):
    session = f"it-webbook-{os.getpid()}"
    h.start("world_server", "world_server", "--domain", domain, "--session", session, "--scene", "start_menu")
    h.wait_for_line("world_server", "message board #1", 30)
    h.start("spectator", "graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--out", os.path.join(h.work, "frames"))
    port = start_view(h, domain, session)
    h.wait_for_line("console", "world 'start_menu' revision 1", 30)
    with open(os.path.join(ASSETS, "scenes", "start_menu.json")) as f:
        spec = [c for c in json.load(f)["controls"] if c["id"] == "book_solar_system"][0]
    first = {t["language"]: t["text"] for t in spec["pages"][0]["text"]}  # its first spread
    driver = start_browser(h.work, SOFTWARE_WEBGL)
    try:
        driver.get(f"http://127.0.0.1:{port}/")
        wait_until("the view of the start menu", 60, lambda: (lambda v: v and v["world"] == "start_menu" and
                   v["frames"] > 5)(page_view(driver)), lambda: str(page_view(driver)) + str(driver.get_log("browser")))
        h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
                "--script", os.path.join(DATA, "book_alice.hand"))
        # Open at its first spread (index 0) as the graphics node draws it: the page's text in the
        # view's language, English, then Japanese after the switch (the book stays open at it
        # about 3 s before alice turns the page).
        h.wait_for_line("spectator", "control 'book_solar_system' of 'start_menu' at index 0, engaged (by alice)", 90)
        book = wait_until("the page's book open at its first spread", 10, lambda: (lambda c: c if c and c["engaged"] and
                          c["index"] == 0 else None)(page_view(driver).get("controls", {}).get("book_solar_system")),
                          lambda: f"the page's controls: {page_view(driver).get('controls')}")
        check(book["page"] == first["en"], f"the open book's page shows {book['page']!r}, not {first['en']!r}")
        # The switch and the look in one script: the book stays open at this spread for a few
        # seconds only (a click through the driver can take longer on a loaded machine).
        book_ja = driver.execute_script("document.querySelector(\"#languages button[data-lang='ja']\").click();"
                                        "return window.handshareView.controls.book_solar_system || null;")
        spread = {t["language"]: t["text"] for t in spec["pages"][max(0, book_ja["index"])]["text"]} if book_ja else {}
        check(book_ja is not None and book_ja["engaged"] and book_ja["page"] == spread.get("ja"),
              f"in Japanese the open book shows {book_ja}, not its spread's {spread.get('ja')!r}")
        # Its picture on the left page: the scene file's image of the spread it is open at, as the
        # console serves it (the asset's bytes), loaded at the image's size.
        picture = wait_until("the open book's picture loaded", 20, lambda: (lambda c: c if c and c["engaged"] and
                             c.get("picture") and c["picture"]["loaded"] else None)(
                                 page_view(driver).get("controls", {}).get("book_solar_system")),
                             lambda: f"the page's controls: {page_view(driver).get('controls')}")
        image_file = os.path.join(ASSETS, spec["pages"][max(0, picture["index"])]["image"])
        from PIL import Image
        with Image.open(image_file) as image:
            size = image.size
        check(picture["picture"]["url"] == "/pictures/" + os.path.basename(image_file) and
              (picture["picture"]["width_px"], picture["picture"]["height_px"]) == size,
              f"the open book's left page shows {picture['picture']}, not {image_file} ({size[0]} x {size[1]})")
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{picture['picture']['url']}", timeout=10) as r:
            served = r.read()
        with open(image_file, "rb") as f:
            check(served == f.read(), f"{picture['picture']['url']} is not {image_file}")
        shot = os.path.join(h.work, "view_book.png")
        driver.save_screenshot(shot)
        h.wait_for_line("world_server", "control book_solar_system by alice: scene 'solar_system'", 90)
        check_page_log(driver, "the view")
    finally:
        driver.quit()
    stop_all(h, "spectator", "console", "alice", "world_server")
    print(f"view_book: the book open at its first spread with its text in English and Japanese, its picture "
          f"{picture['picture']['url']} ({size[0]} x {size[1]}) on its left page; screenshot {shot}")


FIELD_TOLERANCE_M = 1e-6  # the console sends whole micrometres (0.5 um) of the samples' floats; the page's float32 positions


def camera_url(port, frames):
    """The view's URL from a headless graphics node's camera (its camera.json)."""
    camera = wait_until("the graphics node's camera", 30, lambda: read_json(os.path.join(frames, "camera.json")))
    query = urllib.parse.urlencode({"eye": ",".join(map(repr, camera["eye_W_m"])),
                                    "target": ",".join(map(repr, camera["target_W_m"])),
                                    "up": ",".join(map(repr, camera["up_W"])), "fov_y": repr(camera["fov_y_rad"]),
                                    "size": f"{camera['width_px']}x{camera['height_px']}"})
    return f"http://127.0.0.1:{port}/?{query}"


# Snapshots of the page (view.snapshot) taken every `period_ms` for `seconds`, the page going on
# between them (documents arrive): [{"stamps", "hands", "png"}], one per new hands stamp.
SNAPSHOTS_JS = """
const [seconds, periodMs, done] = arguments;
const until = performance.now() + 1000 * seconds;
const shots = [];
const take = () => {
  const s = window.handshareView.snapshot(false);
  const last = shots[shots.length - 1];
  if (!last || JSON.stringify(last.stamps) !== JSON.stringify(s.stamps)) shots.push(s);
  if (performance.now() < until) setTimeout(take, periodMs); else done(shots);
};
take();
"""


def same_moment(shot, row, user, mesh):
    """True when a graphics node's frame (its frame_times.csv row) shows what the page's snapshot
    shows: the user's hand from the same device state and the mesh at the same revision."""
    return (shot["stamps"]["hands"].get(user) is not None and row["hands"].get(user) == shot["stamps"]["hands"][user]
            and row["deformations"].get(mesh) == shot["stamps"]["deformations"].get(mesh))


MOVING_MIN_PAIRS = 3      # matched moments while her hand comes down and presses
MOVING_COMPARED = 6       # of them compared pixel by pixel (evenly spread)
MOVING_MIN_TRAVEL_M = 0.02  # her index fingertip between the first and the last of them
# The press turns the tail's faces (the dent, and the whole tail a little): its mask is where the
# shading changed by more than this, and the two renderers shade differently (the graphics node
# per vertex, OpenGL's fixed-function lighting; three.js per pixel, Phong), so the masks agree
# to a few pixels only (measured 7.5 px, IoU 0.67); the vertices themselves are checked to 1 um.
DENT_DIFF_THRESHOLD = 12
DENT_TOLERANCE_PX = 10.0
DENT_MIN_IOU = 0.5


def case_view_deform(h, domain):
    from PIL import Image

    session = f"it-webdeform-{os.getpid()}"
    os.environ["HANDSHARE_CACHE"] = fem_cache(h.work)
    dump = os.path.join(h.work, "deformation")
    frames = os.path.join(h.work, "frames")
    received_file = os.path.join(h.work, "received_deformation.json")
    h.start("world_server", "world_server", "--domain", domain, "--session", session, "--scene", "dinosaur",
            "--dump-deformation", dump, "--deformation-threshold", "5e-5")
    h.wait_for_line("world_server", "models of 'dinosaur' ready", 400)
    # 8 frames a second: of alice's device states (at least 30 a second) a frame shows about one
    # in four, and the page's snapshots find it among them.
    h.start("spectator", "graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 8, "--out", frames, "--deformation-out", received_file)
    port = start_view(h, domain, session)
    h.wait_for_line("console", "world 'dinosaur' revision 1", 30)
    tail = scene_object("dinosaur", "triceratops_tail")
    mesh = "triceratops_tail"
    driver = start_browser(h.work, SOFTWARE_WEBGL)
    driver.set_script_timeout(60)
    try:
        # The page from the graphics node's camera throughout.
        driver.get(camera_url(port, frames))
        wait_until("the view of the dinosaur world", 60, lambda: (lambda v: v and v["world"] == "dinosaur" and
                   v["meshesLoaded"] + v["meshesFailed"] == 5 and v["frames"] > 5)(page_view(driver)),
                   lambda: str(page_view(driver)) + str(driver.get_log("browser")))
        check(page_view(driver)["meshesFailed"] == 0, f"meshes did not load: {driver.get_log('browser')}")
        # Before alice: the page, and a graphics node frame drawn after it.
        before = driver.execute_script("return window.handshareView.snapshot(false);")
        first = len(frame_times(frames))
        before_row = wait_until("a graphics node frame before alice", 30, lambda: next(
            (r for r in frame_times(frames)[first:] if not r["hands"]), None))
        h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
                "--script", os.path.join(DATA, "tail_alice.hand"))
        h.wait_for_line("alice", "hand script starts at loop time", 120)
        # While her hand comes down and presses (3 s reach, 0.5 s hold, 3 s press).
        moving = driver.execute_async_script(SNAPSHOTS_JS, 8, 100)
        pressed = PressWatch(os.path.join(dump, "triceratops_tail.json"), tail["position_m"], {"alice": (0.27, 0.08)})
        held = wait_until("the tail pressed by alice, held still for 2.5 s", 120, lambda: pressed.still_for(2.5),
                          pressed.explain)
        page = driver.execute_script("const v = window.handshareView; return [v.deformations || {}, "
                                     "v.meshVertices ? v.meshVertices('triceratops_tail') : null];")
        # Held: the page with and without her hand, against a frame drawn after it.
        still = driver.execute_script("return window.handshareView.snapshot(true);")
        drawn_after = len(frame_times(frames))
        wait_until("two graphics node frames after the held page", 30, lambda: len(frame_times(frames)) >= drawn_after + 2)
        check(h.stop("spectator", 20) == 0, "the spectator did not end cleanly")
    finally:
        driver.quit()
    shown, vertices = page
    received = read_json(received_file)
    check(received is not None and "triceratops_tail" in received, f"the graphics node received no field of the tail: {received}")
    field = received["triceratops_tail"]
    check(shown.get("triceratops_tail", {}).get("revision") == field["revision"] == held["revision"],
          f"revisions: the page {shown}, the graphics node {field['revision']}, the world server {held['revision']}")
    count = field["vertex_count"]
    check(vertices is not None and len(vertices["p_MV"]) == 3 * count, f"the page's tail has not the {count} vertices")
    # Vertex v of the page is node v + 1 of the world server's mesh (its surface nodes first).
    nodes = read_inp_nodes(os.path.join(dump, held["mesh"]))
    order_off = max(abs(vertices["p_MV"][3 * v + k] - nodes[v + 1][k]) for v in range(count) for k in range(3))
    check(order_off <= 1e-6, f"the page's vertices are not the world server's nodes in order ({order_off} m off)")
    # Drawn where the graphics node draws them: X_WO p_OV + u_W (the tail is not turned in W).
    q = tail.get("orientation_wxyz", [1.0, 0.0, 0.0, 0.0])
    worst, u_max = 0.0, 0.0
    for v in range(count):
        u = field["u_W_m"].get(str(v), [0.0, 0.0, 0.0])
        u_max = max(u_max, math.sqrt(sum(c * c for c in u)))
        p_OV = vertices["p_MV"][3 * v:3 * v + 3]
        expected = [a + b + c for a, b, c in zip(rotate(q, p_OV), tail["position_m"], u)]
        worst = max(worst, max(abs(a - b) for a, b in zip(vertices["p_WV"][3 * v:3 * v + 3], expected)))
    check(u_max >= 1e-3, f"the tail's largest displacement is {u_max * 1e3:.2f} mm: not a press")
    check(worst <= FIELD_TOLERANCE_M, f"the page draws a vertex of the tail {worst} m from the graphics node's")

    # The pixels. Moving: each snapshot whose stamps a frame shows (alice's device state, the
    # tail's revision) against that frame, by the fingertips' colours.
    rows = frame_times(frames)
    pairs = [(shot, row) for shot in moving
             for row in [next((r for r in rows if same_moment(shot, r, "alice", mesh)), None)] if row]
    check(len(pairs) >= MOVING_MIN_PAIRS, f"{len(pairs)} of the page's {len(moving)} snapshots while alice moved "
          f"show the stamps of one of the graphics node's {len(rows)} frames, under {MOVING_MIN_PAIRS}")
    travel = math.dist(pairs[0][0]["hands"]["alice"][1], pairs[-1][0]["hands"]["alice"][1])
    check(travel >= MOVING_MIN_TRAVEL_M, f"her index fingertip moved {travel * 1e3:.1f} mm between the first and "
          f"the last matched moment: not a moving hand")
    moving_worst, compared = 0.0, 0
    # At most MOVING_COMPARED of them, evenly spread (each costs this script a second or two).
    chosen = min(MOVING_COMPARED, len(pairs))
    compared_pairs = [pairs[round(i * (len(pairs) - 1) / max(1, chosen - 1))] for i in range(chosen)]
    for shot, row in compared_pairs:
        page_masks = colour_masks(decode_png(shot["png"]), FINGERTIP_COLOURS)
        frame_masks = colour_masks(Image.open(row["file"]).convert("RGB"), FINGERTIP_COLOURS)
        for name in FINGERTIP_COLOURS:
            a, b = page_masks[name], frame_masks[name]
            if len(a) < 20 and len(b) < 20:
                continue  # behind the tail or the hand's own fingertip in both
            d, _ = compare_masks(f"{name} at stamps {shot['stamps']}", a, b, row["file"], FRAME_TOLERANCE_PX, 0.0)
            moving_worst, compared = max(moving_worst, d), compared + 1
    check(compared >= 2 * len(compared_pairs), f"only {compared} fingertip masks in {len(compared_pairs)} matched moments")
    # Held: the frame at the page's revision whose fingertips (frames.csv) are where the page
    # drew hers (still: stamps differ, positions do not). What alice changed (her hand and the
    # dent) against the frames before her; the dent alone (the page without her hand; the
    # frame with the page's hand mask, grown by 3 px, left out).
    drawn = {}
    with open(os.path.join(frames, "frames.csv")) as f:
        next(f)
        for line in f:
            frame, _, user, finger, x, y, z, _ = line.strip().split(",")
            if user == "alice":
                drawn.setdefault(int(frame), {})[int(finger)] = [float(x), float(y), float(z)]
    tips = still["hands"]["alice"]
    held_row = next((r for r in reversed(rows) if r["deformations"].get(mesh) == still["stamps"]["deformations"].get(mesh)
                     and r["frame"] in drawn and len(drawn[r["frame"]]) == 5 and
                     max(math.dist(drawn[r["frame"]][k], tips[k]) for k in range(5)) <= TIP_TOLERANCE_M), None)
    check(held_row is not None, f"no graphics node frame shows the tail at revision "
          f"{still['stamps']['deformations'].get(mesh)} with alice's fingertips where the page drew them: {tips}")
    page_now, page_bare, page_before = decode_png(still["png"]), decode_png(still["bare"]), decode_png(before["png"])
    for name, image in (("page_held", page_now), ("page_held_without_hands", page_bare), ("page_before", page_before)):
        image.save(os.path.join(h.work, name + ".png"))
    frame_now = Image.open(held_row["file"]).convert("RGB")
    frame_before = Image.open(before_row["file"]).convert("RGB")
    # Only near what changed on the page (the graphics node's caption and labels fall out).
    changed_page = difference_mask(page_now, page_before)
    check(changed_page, "alice changed nothing on the page")
    xs, ys = [p[0] for p in changed_page], [p[1] for p in changed_page]
    box = (min(xs) - 40, min(ys) - 40, max(xs) + 40, max(ys) + 40)
    near = lambda mask: {p for p in mask if box[0] <= p[0] <= box[2] and box[1] <= p[1] <= box[3]}
    changed_frame = near(difference_mask(frame_now, frame_before))
    d_all, iou_all = compare_masks("what alice changed (her hand and the dent)", changed_page, changed_frame,
                                   f"{held_row['file']} against {before_row['file']}", HAND_MASK_TOLERANCE_PX,
                                   HAND_MASK_MIN_IOU)
    hand_page = difference_mask(page_now, page_bare)
    grown = {(x + i, y + j) for x, y in hand_page for i in range(-3, 4) for j in range(-3, 4)}
    dent_page = {p for p in difference_mask(page_bare, page_before, DENT_DIFF_THRESHOLD) if p not in grown}
    dent_frame = {p for p in near(difference_mask(frame_now, frame_before, DENT_DIFF_THRESHOLD)) if p not in grown}
    d_dent, iou_dent = compare_masks("the dent", dent_page, dent_frame, held_row["file"], DENT_TOLERANCE_PX,
                                     DENT_MIN_IOU)
    stop_all(h, "console", "alice", "world_server")
    print(f"view_deform: the tail pressed {u_max * 1e3:.2f} mm, its {count} vertices drawn within {worst:.1e} m of the "
          f"graphics node's (revision {field['revision']}), in the world server's node order ({order_off:.1e} m)")
    print(f"view_deform: while alice's hand came down and pressed (her index fingertip {travel * 1e3:.0f} mm between the "
          f"first and the last matched moment), {len(pairs)} of the page's "
          f"{len(moving)} snapshots had the stamps of a graphics node frame; in {len(compared_pairs)} of them {compared} "
          f"fingertip masks within "
          f"{moving_worst:.1f} px; held (frame {held_row['frame']}): what she changed ({len(changed_page)} and "
          f"{len(changed_frame)} px) {d_all:.1f} px (IoU {iou_all:.2f}), the dent alone ({len(dent_page)} and "
          f"{len(dent_frame)} px) {d_dent:.1f} px (IoU {iou_dent:.2f})")


def post_visit(base, body, token):
    """POST /api/visit as a script would: (status, body)."""
    return post_json(base, "/api/visit", body, token)


def fill_questionnaire(driver, visitor, answers, token):
    """Chooses the visitor, ticks every score of `answers` ({kind: {question: score}}), types the
    token and presses Send, as a visitor on a tablet would; returns the status the page shows."""
    result = driver.find_element(By.ID, "visit-result")
    driver.execute_script("arguments[0].removeAttribute('data-status'); arguments[0].textContent = '';", result)
    Select(driver.find_element(By.ID, "visitor")).select_by_value(visitor)
    for kind, scores in answers.items():
        for question, score in scores.items():
            box = driver.find_element(By.ID, f"q-{kind}-{question}-{score}")
            driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", box)
            box.click()
            check(box.is_selected(), f"the page did not tick {kind} {question} {score}")
    field = driver.find_element(By.ID, "visit-token")
    field.clear()
    field.send_keys(token)
    driver.find_element(By.ID, "visit-send").click()
    status = wait_until(f"the page's answer to sending {visitor}'s questionnaire", 20,
                        lambda: result.get_attribute("data-status"))
    return status, result.text


# What alice answers: two kinds of control she used; arrows and levers she leaves empty.
VISIT_ANSWERS = {"button": {"ease": 6, "naturalness": 5, "satisfaction": 7},
                 "book": {"ease": 4, "naturalness": 3, "satisfaction": 2}}
VISIT_MINUTES = 0.05  # 3 s


def case_visit(h, domain):
    session = f"it-webvisit-{os.getpid()}"
    token, token_file = write_token(h.work)
    log_db = os.path.join(h.work, "session.sqlite")
    h.start("world_server", "world_server", "--domain", domain, "--session", session,
            "--visit-minutes", VISIT_MINUTES, "--log", log_db)
    h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
            "--device", "sim", "--script", os.path.join(DATA, "alice.hand"))
    h.wait_for_line("world_server", "member joined: user=alice", 60)
    # Her turn ends 3 s after her join, once, and the board says so in both languages.
    h.wait_for_line("world_server", "visitor's turn ended: user=alice", 30)
    turn_s = float(re.search(r"visitor's turn ended: user=alice after ([0-9.]+) s", h.log("world_server")).group(1))
    check(turn_s >= VISIT_MINUTES * 60, f"alice's turn ended after {turn_s} s, before its {VISIT_MINUTES * 60} s")
    check("message board #2: Thank you, alice: your 0.05 minutes are over." in h.log("world_server"),
          "the world server did not put the turn's end on the board")
    port = start_view(h, domain, session, "--name", "visit-console", "--token-file", token_file)
    base = f"http://127.0.0.1:{port}"

    def boards():
        with urllib.request.urlopen(base + "/api/state", timeout=10) as r:
            b = json.loads(r.read())["boards"]
        return b if "en" in b and "Thank you, alice" in b["en"]["text"] else None
    b = wait_until("the console's board saying alice's turn is over", 30, boards, poll_s=CONSOLE_POLL_S)
    check("alice" in b["ja"]["text"] and "終わりました" in b["ja"]["text"],
          f"the Japanese board does not say the turn is over: {b['ja']}")

    driver = start_browser(h.work, phone=(412, 1700))  # a phone's width (a tall one: the screenshot shows more)
    try:
        driver.get(base + "/visit")
        wait_until("the questionnaire offering alice and showing the board", 30,
                   lambda: "alice" in driver.execute_script("return window.handshareVisit.visitors;") and
                   "Thank you, alice" in driver.find_element(By.ID, "board-en").text,
                   lambda: driver.find_element(By.TAG_NAME, "body").text)
        width = driver.execute_script("return [document.documentElement.scrollWidth, window.innerWidth];")
        check(width[1] == 412 and width[0] <= width[1], f"the questionnaire is wider than a phone's 412 px: {width}")
        # A wrong token from the page, none and a wrong one from a script: 401, nothing sent.
        status, text = fill_questionnaire(driver, "alice", VISIT_ANSWERS, "not-the-token-" + secrets.token_hex(8))
        check(status == "401", f"a wrong token from the page got {status} ({text}), not 401")
        body = {"visitor": "alice", "answers": {"lever": {"ease": 1, "naturalness": 1, "satisfaction": 1}}}
        status, text = post_visit(base, body, None)
        check(status == 401, f"no token got {status} ({text}), not 401")
        status, text = post_visit(base, body, token + "x")
        check(status == 401, f"a wrong token got {status} ({text}), not 401")
        # The token: 202, and the world server takes the answers.
        status, text = fill_questionnaire(driver, "alice", VISIT_ANSWERS, token)
        check(status == "202", f"the questionnaire from the page got {status} ({text}), not 202")
        h.wait_for_line("world_server", "questionnaire: visitor=alice sent by visit-console, 6 answers", 30)
        driver.execute_script("window.scrollTo(0, 0);")
        shot = os.environ.get("HANDSHARE_VISIT_SCREENSHOT") or os.path.join(h.work, "visit.png")
        driver.save_screenshot(shot)
        check_page_log(driver, "the page", ignore="/api/visit")
    finally:
        driver.quit()
    check(h.stop("console", 30) == 0, "web_console failed")
    check(h.log("console").count("questionnaire of visitor alice sent") == 1,
          "the console sent other questionnaires than the one with the token")
    check(h.stop("alice", 30) == 0, "haptic_node alice failed")
    check(h.stop("world_server", 30) == 0, "world_server failed")

    report_exe = os.path.join(h.bin_dir, "world_server", "session_report")
    report = subprocess.run([report_exe, log_db], capture_output=True, text=True, timeout=60)
    check(report.returncode == 0, f"session_report failed: {report.stderr}")
    text = report.stdout
    check("questionnaire (the paper's Fig. 16 and Table 3): 1 questionnaire(s)" in text,
          f"session_report does not count one questionnaire (the refused ones stored nothing):\n{text}")
    # One visitor: n 1, the score as the mean, no spread (-); the kinds she left empty: n 0, -.
    for kind in ("arrow", "book", "button", "lever"):
        for question in ("ease", "naturalness", "satisfaction"):
            score = VISIT_ANSWERS.get(kind, {}).get(question)
            row = (rf"^  {kind}\s+{question}\s+1\s+{score}\.00\s+-$" if score else
                   rf"^  {kind}\s+{question}\s+0\s+-\s+-$")
            check(re.search(row, text, re.M), f"session_report has no row '{row}':\n{text}")
    check(re.search(r"^visitors' turns ended: 1$", text, re.M) and re.search(r"^  alice\s+[0-9.]+", text, re.M),
          f"session_report does not show alice's turn:\n{text}")
    csv = subprocess.run([report_exe, log_db, "--csv"], capture_output=True, text=True, timeout=60).stdout
    check(",questionnaire,book/satisfaction,mean,2\n" in csv, f"the CSV lacks the book's satisfaction:\n{csv}")
    print(f"visit: alice's turn ended after {turn_s} s and the board said so (en, ja); wrong tokens 401; "
          f"her answers from the page in session_report's questionnaire table; screenshot {shot}")


def page_table4(driver):
    """The page's Table 4 as {kind: {column: text}}, read in one script (the page redraws it)."""
    rows = driver.execute_script(
        "return Array.from(document.querySelectorAll('#table4 tbody tr'), (r) => "
        "[r.dataset.kind, Object.fromEntries(Array.from(r.cells).slice(1).map((c) => [c.className.split(' ')[1], c.textContent]))]);")
    return {kind: cells for kind, cells in rows}


def case_operator_tour(h, domain):
    session = f"it-webtour-{os.getpid()}"
    token, token_file = write_token(h.work)
    log_db = os.path.join(h.work, "session.sqlite")
    h.start("world_server", "world_server", "--domain", domain, "--session", session, "--scene", "start_menu",
            "--log", log_db)
    h.wait_for_line("world_server", "message board #1", 30)
    # The console before alice: it hears every control event the world server logs.
    port = start_view(h, domain, session, "--name", "operator-console", "--token-file", token_file)
    base = f"http://127.0.0.1:{port}"
    h.wait_for_line("console", "world 'start_menu' revision 1", 30)
    h.wait_for_line("world_server", "member joined: user=operator-console", 30)
    driver = start_browser(h.work)
    try:
        driver.get(base + "/operator")
        wait_until("the page showing the start menu", 30, lambda: driver.find_element(By.ID, "world").text == "start_menu")
        # Alice opens the solar system's book and turns its page: book events, and the solar system.
        h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
                "--device", "sim", "--script", os.path.join(DATA, "book_alice.hand"))
        h.wait_for_line("world_server", "by alice: scene 'solar_system'", 120)
        wait_until("the page showing the solar system", 20,
                   lambda: driver.find_element(By.ID, "world").text == "solar_system")
        wait_until("alice as a visitor with an end-turn button", 20,
                   lambda: driver.find_elements(By.CSS_SELECTOR, "#visitors button[data-visitor='alice']"))

        # A command needs a visitor who is there; refused, it changes nothing. (The token, a bad
        # body: web_console_test's WebServerTest; five actions at most at once per address: this
        # one and the four below.)
        status, text = post_json(base, "/api/command", {"command": "end_turn", "visitor": "mallory"}, token)
        check(status == 404, f"ending the turn of nobody got {status} ({text}), not 404")

        # The dinosaurs through the solar system's arrow (a control event of the console's: an
        # arrow's hit in Table 4), then back to the solar system, which no control of the
        # dinosaur world goes to: the operator's command.
        status, text = send_from_page(driver, "dinosaur", token)
        check(status == 202, f"sending the session to a linked world got {status} ({text}), not 202")
        h.wait_for_line("world_server", "control arrow_next by operator-console: scene 'dinosaur'", 30)
        wait_until("the page showing the dinosaurs", 20, lambda: driver.find_element(By.ID, "world").text == "dinosaur")
        status, text = send_from_page(driver, "solar_system", token)
        check(status == 202, f"sending the session to an unlinked world got {status} ({text}), not 202")
        h.wait_for_line("world_server", "operator command go_to_world by operator-console: scene 'solar_system'", 30)
        wait_until("the page showing the solar system again", 20,
                   lambda: driver.find_element(By.ID, "world").text == "solar_system")

        # Restart the tour: the start menu and its first message again, alice's turn begun afresh.
        status, text = click_and_wait(driver, element_id="restart-tour")
        check(status == 202, f"restarting the tour from the page got {status} ({text}), not 202")
        h.wait_for_line("world_server", "operator command restart_tour by operator-console: scene 'start_menu'", 30)
        h.wait_for_line("world_server", "visitor's turn ended: user=alice after", 30)
        check("(by the operator, operator-console)" in h.log("world_server"),
              "the world server does not say the operator ended alice's turn at the restart")
        wait_until("the page back in the start menu with its welcome", 20,
                   lambda: driver.find_element(By.ID, "world").text == "start_menu" and
                   "Welcome" in driver.find_element(By.ID, "board-en").text)

        # End alice's turn: the board thanks her, in both languages.
        status, text = click_and_wait(driver, css="#visitors button[data-visitor='alice']")
        check(status == 202, f"ending alice's turn from the page got {status} ({text}), not 202")
        wait_until("the page's board thanking alice", 20,
                   lambda: "Thank you, alice: your turn is over." in driver.find_element(By.ID, "board-en").text)
        check("alice" in driver.find_element(By.ID, "board-ja").text, "the Japanese board does not name alice")
        page = page_table4(driver)
        driver.execute_script("window.scrollTo(0, document.body.scrollHeight);")
        driver.save_screenshot(os.path.join(h.work, "operator_tour.png"))
        check_page_log(driver, "the page", ignore="/api/")
    finally:
        driver.quit()
    stop_all(h, "console", "alice", "world_server")
    log = h.log("world_server")
    # The refused requests were never published: the world server took exactly the three sent.
    check("operator_command in 3;" in log, "the world server took other operator commands than the three sent")
    check(log.count("(by the operator, operator-console)") == 2,
          "the world server did not end alice's turn once at the restart and once at the end of her turn")

    # The page's Table 4 is the session log's (session_report's control_kind rows).
    report_exe = os.path.join(h.bin_dir, "world_server", "session_report")
    csv = subprocess.run([report_exe, log_db, "--csv"], capture_output=True, text=True, timeout=60).stdout
    logged = {}
    for line in csv.splitlines():
        fields = line.split(",")
        if len(fields) == 5 and fields[1] == "control_kind":
            logged.setdefault(fields[2], {})[fields[3]] = fields[4]
    check(logged, f"session_report has no Table 4 by kind:\n{csv}")
    check(set(page) == set(logged), f"the page's kinds {sorted(page)} are not the log's {sorted(logged)}")
    for kind, row in logged.items():
        for column, field in (("controls", "controls"), ("hits", "hits"), ("misses", "misses"), ("users", "users")):
            check(page[kind][column] == row[field],
                  f"{kind} {column}: the page shows {page[kind][column]}, the log {row[field]}")
        if int(row["error_n"]) > 0:
            check(abs(float(page[kind]["error"]) - 1000 * float(row["error_mean_m"])) <= 0.05 + 1e-9,
                  f"{kind} hit error: the page {page[kind]['error']} mm, the log {row['error_mean_m']} m")
        check(abs(float(page[kind]["misses-per-user"] or 0) - float(row["misses_per_user_mean"])) <= 0.005 + 1e-9,
              f"{kind} misses per user: the page {page[kind]['misses-per-user']}, the log {row['misses_per_user_mean']}")
    check(int(logged.get("book", {}).get("hits", 0)) >= 2 and int(logged.get("arrow", {}).get("hits", 0)) == 1,
          f"alice's book events or the console's arrow are not in the log:\n{csv}")
    turns = [line for line in csv.splitlines() if ",turn," in line and line.endswith(",alice")]
    check(len(turns) == 2, f"session_report has {len(turns)} turns of alice, not 2 (the restart's and the end's):\n{csv}")
    kinds = ", ".join(f"{k} {v['hits']} hits" for k, v in logged.items())
    print(f"operator tour: Table 4 on the page equals the log's ({kinds}); "
          f"an unlinked world, the tour's restart and alice's turn's end from the page reached the world server")


if __name__ == "__main__":
    sys.exit(run_cases({"operator": case_operator, "tls": case_tls, "view": case_view, "view_bodies": case_view_bodies,
                        "view_deform": case_view_deform, "view_book": case_view_book, "visit": case_visit,
                        "operator_tour": case_operator_tour}))
