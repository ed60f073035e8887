// The questionnaire at the end of a visitor's turn (the paper's section 1.7.1, Fig. 16): for
// each kind of control, ease, naturalness and satisfaction on a 1-7 scale. The page lists the
// visitors (haptic members) the console's state has named since it opened, shows the board (it
// says when a turn is over) and POSTs the answers to /api/visit with the operator's token (kept
// in the page only, never stored). Text from the session goes in with textContent only.
"use strict";

const $ = (id) => document.getElementById(id);
const KINDS = [
  {id: "button", en: "Buttons", ja: "ボタン"},
  {id: "arrow", en: "Arrows", ja: "矢印"},
  {id: "lever", en: "Levers", ja: "レバー"},
  {id: "book", en: "Books", ja: "本"},
];
const QUESTIONS = [
  {id: "ease", en: "Easy to choose and move between worlds with?", ja: "世界を選んだり移動したりしやすかったですか"},
  {id: "naturalness", en: "Natural to handle?", ja: "自然に操作できましたか"},
  {id: "satisfaction", en: "How satisfied were you with it?", ja: "どのくらい満足しましたか"},
];
const visitors = [];  // every haptic member's user seen, in order
window.handshareVisit = {visitors: visitors, sent: 0};

function text(id, value) {
  $(id).textContent = value === undefined || value === null ? "" : String(value);
}

function element(tag, cls, content, lang) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (content !== undefined) e.textContent = content;
  if (lang) e.lang = lang;
  return e;
}

function buildForm() {
  const kinds = $("kinds");
  for (const k of KINDS) {
    const section = element("section", "kind");
    section.dataset.kind = k.id;
    const title = element("h2", "", k.en + " ");
    title.appendChild(element("span", "", k.ja, "ja"));
    section.appendChild(title);
    for (const q of QUESTIONS) {
      const fieldset = element("fieldset", "scale");
      const legend = element("legend", "", q.en + " ");
      legend.appendChild(element("span", "", q.ja, "ja"));
      fieldset.appendChild(legend);
      for (let v = 1; v <= 7; ++v) {
        const label = element("label", "score");
        const input = document.createElement("input");
        input.type = "radio";
        input.name = k.id + "-" + q.id;
        input.value = String(v);
        input.id = "q-" + k.id + "-" + q.id + "-" + v;
        label.appendChild(input);
        label.appendChild(element("span", "", String(v)));
        fieldset.appendChild(label);
      }
      section.appendChild(fieldset);
    }
    kinds.appendChild(section);
  }
}

function showVisitors(members) {
  let added = false;
  for (const m of members) {
    if (m.kind === "haptic" && !visitors.includes(m.user)) {
      visitors.push(m.user);
      added = true;
    }
  }
  if (!added) return;
  const select = $("visitor");
  const chosen = select.value;
  select.replaceChildren();
  for (const v of visitors) {
    const option = element("option", "", v);
    option.value = v;
    select.appendChild(option);
  }
  if (chosen) select.value = chosen;
}

function show(state) {
  text("session", state.session);
  for (const lang of ["en", "ja"]) {
    const b = state.boards[lang];
    text("board-" + lang, b ? b.text + " " + b.next_action : "");
  }
  showVisitors(state.members);
  $("visit-send").disabled = !state.console.actions_enabled;
}


// The answers as /api/visit takes them, or a string saying what is missing.
function collect() {
  const answers = {};
  for (const k of KINDS) {
    const scores = {};
    let given = 0;
    for (const q of QUESTIONS) {
      const checked = document.querySelector("input[name='" + k.id + "-" + q.id + "']:checked");
      if (checked) {
        scores[q.id] = Number(checked.value);
        ++given;
      }
    }
    if (given === QUESTIONS.length) answers[k.id] = scores;
    else if (given > 0) return k.en + ": answer all three questions, or none";
  }
  if (Object.keys(answers).length === 0) return "answer the questions of at least one kind of control";
  return answers;
}

async function send(event) {
  event.preventDefault();
  const result = $("visit-result");
  const answers = collect();
  if (typeof answers === "string") {
    result.dataset.status = "incomplete";
    result.textContent = answers;
    return;
  }
  text("visit-result", "sending ...");
  try {
    const response = await fetch("/api/visit", {
      method: "POST",
      headers: {"Content-Type": "application/json", "Authorization": "Bearer " + $("visit-token").value},
      body: JSON.stringify({visitor: $("visitor").value, answers: answers}),
      cache: "no-store",
    });
    const body = await response.json().catch(() => ({}));
    result.dataset.status = String(response.status);
    if (response.ok) {
      ++window.handshareVisit.sent;
      result.textContent = response.status + ": thank you, " + body.visitor + " (" + body.answers +
          " answers) \u3042\u308a\u304c\u3068\u3046\u3054\u3056\u3044\u307e\u3057\u305f";
    } else {
      result.textContent = response.status + ": " + (body.error || response.statusText);
    }
  } catch (e) {
    text("visit-result", "failed: " + e);
  }
}

buildForm();
$("visit").addEventListener("submit", send);
connectState(show);
