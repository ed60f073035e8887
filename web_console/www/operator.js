// The operator's page: the console pushes the whole state over a WebSocket (at most 5 times a
// second); this script shows it. Text from the session goes in with textContent only, never as
// markup. The actions (a world change, restarting the tour, ending a visitor's turn) are POSTs
// with the token the operator types (kept in the page only, never stored).
"use strict";

const $ = (id) => document.getElementById(id);
let lastRoutes = "";

function text(id, value) {
  $(id).textContent = value === undefined || value === null ? "" : String(value);
}

function fixed(v, digits) {
  return typeof v === "number" && isFinite(v) ? v.toFixed(digits) : "";
}

function cell(row, value, cls) {
  const td = document.createElement("td");
  td.textContent = value;
  if (cls) td.className = cls;
  row.appendChild(td);
  return td;
}

// A station's kind as the page names it: the world server's tick first, then haptic stations,
// screens, guides.
const KINDS = {world_server: [-1, "world server"], haptic: [0, "station"], graphics: [1, "screen"],
               audio_guide: [2, "guide"]};

function showStations(stations) {
  const body = $("stations").querySelector("tbody");
  body.replaceChildren();
  const order = (s) => (KINDS[s.kind] || [3])[0];
  const sorted = stations.slice().sort((a, b) => order(a) - order(b) || (a.node < b.node ? -1 : a.node > b.node ? 1 : 0));
  for (const s of sorted) {
    const tr = document.createElement("tr");
    tr.dataset.user = s.user;
    tr.dataset.node = s.node;
    tr.dataset.kind = s.kind;
    if (s.age_s > 3) tr.className = "stale";
    cell(tr, (KINDS[s.kind] || [3, s.kind || "?"])[1], "kind");
    cell(tr, s.user, "user");
    cell(tr, s.device, "device");
    cell(tr, fixed(s.rate_Hz, 1), "num rate");
    cell(tr, fixed(s.jitter_p99_us, 0), "num jitter");
    cell(tr, fixed(s.step_p99_us, 0), "num step");
    cell(tr, String(s.overruns), "num overruns" + (s.overruns > 0 ? " bad" : ""));
    cell(tr, String(s.resyncs), "num resyncs");
    cell(tr, String(s.faults), "num faults" + (s.faults > 0 ? " bad" : ""));
    cell(tr, String(s.deadline_misses), "num deadlines" + (s.deadline_misses > 0 ? " bad" : ""));
    cell(tr, fixed(s.sent_bytes_per_s, 0), "num sent");
    cell(tr, String(s.samples_dropped), "num dropped");
    cell(tr, fixed(s.age_s, 1), "num age");
    body.appendChild(tr);
  }
}

// The worlds the current one links to first (the console actuates the control that goes
// there, as a hand would), then every other world but the current one (an operator's command).
function showRoutes(routes, worlds, current) {
  const key = JSON.stringify([routes, worlds, current]);
  if (key === lastRoutes) return;  // keep the operator's choice while the world stays
  lastRoutes = key;
  const select = $("goto-world");
  select.replaceChildren();
  const linked = new Set();
  for (const r of routes) {
    const option = document.createElement("option");
    option.value = r.world;
    option.textContent = r.world + " (" + r.control + ")";
    select.appendChild(option);
    linked.add(r.world);
  }
  for (const w of worlds || []) {
    if (linked.has(w) || w === current) continue;
    const option = document.createElement("option");
    option.value = w;
    option.textContent = w + " (operator command)";
    select.appendChild(option);
  }
}

function mm(summary) {
  return summary && summary.n > 0 ? (summary.mean * 1000).toFixed(1) : "";
}

function showTable4(table) {
  const body = $("table4").querySelector("tbody");
  body.replaceChildren();
  for (const k of table.kinds) {
    const tr = document.createElement("tr");
    tr.dataset.kind = k.kind;
    cell(tr, k.kind);
    cell(tr, String(k.controls), "num controls");
    cell(tr, String(k.hits), "num hits");
    cell(tr, String(k.misses), "num misses");
    cell(tr, mm(k.error_m), "num error");
    cell(tr, k.error_m.n > 1 ? (k.error_m.sd * 1000).toFixed(1) : "", "num error-sd");
    cell(tr, String(k.misses_per_user.n), "num users");
    cell(tr, fixed(k.misses_per_user.mean, 2), "num misses-per-user");
    cell(tr, fixed(k.misses_per_user.sd, 2), "num misses-per-user-sd");
    body.appendChild(tr);
  }
  text("table4-note", table.control_events + " control events since the console started");
}

// Every visitor (a haptic member) with a button that ends their turn now.
function showVisitors(members, enabled) {
  const list = $("visitors");
  const visitors = members.filter((m) => m.kind === "haptic").map((m) => m.user);
  const key = JSON.stringify([visitors, enabled]);
  if (list.dataset.key === key) return;
  list.dataset.key = key;
  list.replaceChildren();
  for (const user of visitors) {
    const li = document.createElement("li");
    const button = document.createElement("button");
    button.type = "button";
    button.dataset.visitor = user;
    button.textContent = "End " + user + "'s turn";
    button.disabled = !enabled;
    button.addEventListener("click", () => post("/api/command", {command: "end_turn", visitor: user}));
    li.appendChild(button);
    list.appendChild(li);
  }
}

function show(state) {
  text("session", state.session);
  const w = state.world;
  text("world", w ? w.scene : "none yet");
  text("title", w ? w.title : "");
  text("revision", w ? w.revision : "");
  text("tick", w ? fixed(w.tick_Hz, 0) + " Hz" : "");
  text("gravity", w ? fixed(w.gravity_z_m_per_s2, 2) + " m/s\u00b2" : "");
  text("objects", w ? w.objects : "");
  for (const lang of ["en", "ja"]) {
    const b = state.boards[lang];
    text("board-" + lang, b ? b.text + " " + b.next_action : "");
  }
  showStations(state.stations);
  const members = $("members");
  members.replaceChildren();
  for (const m of state.members) {
    const li = document.createElement("li");
    li.textContent = m.user + " (" + m.kind + (m.device ? ", " + m.device : "") + ")";
    members.appendChild(li);
  }
  showRoutes(state.routes, state.worlds, w ? w.scene : "");
  if (state.table4) showTable4(state.table4);
  showVisitors(state.members, state.console.actions_enabled);
  $("goto-send").disabled = !state.console.actions_enabled;
  $("restart-tour").disabled = !state.console.actions_enabled;
  text("console", "console " + state.console.name + ": " + state.console.viewers + " viewer(s), " +
       state.console.viewers_dropped + " dropped; " + state.console.samples_refused + " samples refused" +
       (state.console.actions_enabled ? "" : "; actions are off (no token file)"));
}


// An action: a POST with the token the operator typed; the answer goes in the status line.
async function post(path, request) {
  const token = $("goto-token").value;
  text("goto-result", "sending " + JSON.stringify(request) + " ...");
  try {
    const response = await fetch(path, {
      method: "POST",
      headers: {"Content-Type": "application/json", "Authorization": "Bearer " + token},
      body: JSON.stringify(request),
      cache: "no-store",
    });
    const body = await response.json().catch(() => ({}));
    const result = $("goto-result");
    result.dataset.status = String(response.status);
    let done = "";
    if (body.world) done = "sent to " + body.world + (body.control ? " (control " + body.control + ")" : " (operator command)");
    else if (body.command === "restart_tour") done = "the tour restarts";
    else if (body.command === "end_turn") done = body.visitor + "'s turn ends";
    result.textContent = response.status + ": " + (response.ok ? done : (body.error || response.statusText));
  } catch (e) {
    text("goto-result", "failed: " + e);
  }
}

$("goto").addEventListener("submit", (event) => {
  event.preventDefault();
  post("/api/world", {world: $("goto-world").value});
});
$("restart-tour").addEventListener("click", () => post("/api/command", {command: "restart_tour"}));
connectState(show);
