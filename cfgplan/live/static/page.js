// cfgplan live page: reads /events (server-sent events) and /drawing.svg; sends nothing.
// Text from the run is always set as text (textContent), never parsed as HTML.
"use strict";

const page = {
  drawing: -1, // the number of the drawing shown
  loading: false,
  seen: 0, // the last timeline entry shown
  state: null,
  disconnected: null, // when the page lost the run (seconds since the epoch), or null
};

function $(id) {
  return document.getElementById(id);
}

function element(tag, className, text) {
  const node = document.createElement(tag);
  if (className) node.className = className;
  if (text !== undefined && text !== null) node.textContent = String(text);
  return node;
}

function seconds(t) {
  const s = page.state;
  if (!s || !s.started || t === null || t === undefined) return "";
  return "+" + (t - s.started).toFixed(1) + " s";
}

function cost(value) {
  return value === null || value === undefined ? "-" : String(value);
}

// -- the timeline ----------------------------------------------------------

function addEntries(entries) {
  const list = $("timeline");
  for (const entry of entries) {
    if (entry.seq <= page.seen) continue;
    page.seen = entry.seq;
    const item = element("li", entry.kind);
    item.dataset.seq = entry.seq;
    item.dataset.kind = entry.kind;
    item.dataset.t = entry.t; // the event's time (the trace's t)
    item.dataset.shown = Date.now() / 1000; // when it reached this page
    item.append(element("span", "when", seconds(entry.t) + " · cycle " + entry.cycle));
    item.append(element("span", "kind", entry.kind));
    item.append(element("span", "text", entry.robot + ": " + entry.text));
    if (entry.cause) item.append(element("span", "cause", entry.cause));
    list.prepend(item);
  }
  while (list.children.length > 300) list.lastElementChild.remove();
}

// -- the drawing -------------------------------------------------------------

async function loadDrawing(number) {
  if (page.loading) return;
  page.loading = true;
  try {
    const box = $("diagram");
    const dot = $("dot");
    if (number === 0) {
      box.replaceChildren(element("p", "muted", "no configuration runs"));
      dot.hidden = true;
      page.drawing = 0;
      return;
    }
    const answer = await fetch("/drawing.svg", { cache: "no-store" });
    const shown = Number(answer.headers.get("X-Drawing") || number);
    if (answer.ok) {
      const parsed = new DOMParser().parseFromString(await answer.text(), "image/svg+xml");
      const svg = parsed.documentElement;
      svg.querySelectorAll("script, foreignObject").forEach((n) => n.remove());
      box.replaceChildren(document.importNode(svg, true));
      dot.hidden = true;
    } else {
      const source = await fetch("/drawing.dot", { cache: "no-store" });
      box.replaceChildren(
        element("p", "muted", "no Graphviz layout engine on this machine: the DOT source")
      );
      dot.textContent = await source.text();
      dot.hidden = false;
    }
    page.drawing = shown;
    if (page.state) colour(page.state);
  } catch (error) {
    // the next state message tries again
  } finally {
    page.loading = false;
  }
}

function setClass(node, prefix, value) {
  for (const name of [...node.classList]) {
    if (name.startsWith(prefix)) node.classList.remove(name);
  }
  node.classList.add(prefix + value);
}

function colour(state) {
  const box = $("diagram");
  for (const edge of box.querySelectorAll("g.edge[data-input]")) {
    const input = state.inputs[edge.dataset.input];
    setClass(edge, "input-", input ? input.state : "unknown");
  }
  for (const node of box.querySelectorAll("g.node[data-resource]")) {
    const failed = Object.prototype.hasOwnProperty.call(state.failed, node.dataset.resource);
    node.classList.toggle("failed", failed);
    let mark = node.querySelector("text.failed-mark");
    if (failed && !mark) {
      const shape = node.querySelector("polygon, path");
      if (shape) {
        const box = shape.getBBox();
        mark = document.createElementNS("http://www.w3.org/2000/svg", "text");
        mark.setAttribute("class", "failed-mark");
        mark.setAttribute("x", box.x + box.width); // above the box's right corner
        mark.setAttribute("y", box.y - 3);
        mark.setAttribute("text-anchor", "end");
        mark.textContent = "✕ failed";
        node.append(mark);
      }
    } else if (!failed && mark) {
      mark.remove();
    }
  }
  for (const group of box.querySelectorAll("g.cluster[data-robot]")) {
    const robot = state.robots[group.dataset.robot];
    setClass(group, "robot-", robot ? robot.state : "unknown");
  }
}

// -- tables --------------------------------------------------------------------

function robots(state) {
  const body = $("robots").tBodies[0];
  const now = Date.now() / 1000;
  const rows = [];
  for (const [name, robot] of Object.entries(state.robots)) {
    const row = element("tr");
    row.append(element("td", "", name + (name === state.coordinator ? " (coordinator)" : "")));
    const cell = element("td");
    // Disconnected, the page knows nothing of the robots now: their last state
    // is not shown as if it held (a robot that ran is not "running" still).
    const known = page.disconnected === null ? robot.state : "unknown";
    const said = page.disconnected === null ? robot.state : "unknown (was " + robot.state + ")";
    cell.append(element("span", "state " + known, said));
    row.append(cell);
    row.append(element("td", "number", robot.cycle === null ? "-" : robot.cycle));
    const last = robot.t === null ? null : Math.max(0, now - robot.t);
    row.append(element("td", "number", last === null ? "-" : last.toFixed(1) + " s ago"));
    rows.push(row);
  }
  body.replaceChildren(...rows);
}

function fallbacks(state) {
  const note = $("fallbacks-note");
  const table = $("fallbacks");
  if (state.fallbacks === null) {
    note.textContent = state.fallbacks_note;
    note.hidden = false;
    table.hidden = true;
    return;
  }
  note.hidden = true;
  table.hidden = false;
  const rows = [];
  for (const f of state.fallbacks) {
    const row = element("tr");
    if (Object.prototype.hasOwnProperty.call(state.failed, f.resource)) row.className = "failed";
    row.append(element("td", "", f.resource));
    row.append(element("td", "", f.kind));
    if (!f.known) row.append(element("td", "muted", "computing…"));
    else if (f.cost === null) row.append(element("td", "none", "none admissible"));
    else row.append(element("td", "number", f.cost));
    row.append(element("td", "", (f.robots || []).join(", ")));
    row.append(element("td", "", (f.stopped || []).join(", ")));
    row.append(element("td", "", (f.started || []).join(", ")));
    rows.push(row);
  }
  table.tBodies[0].replaceChildren(...rows);
}

function show(state) {
  page.state = state;
  $("title").textContent = state.title;
  document.title = "cfgplan live: " + state.title;
  const running = state.drawing === 0 ? "nothing runs" : "cost " + cost(state.cost);
  $("configuration").textContent =
    state.configuration === 0 ? "(the first, " + running + ")" : "(switch " + state.configuration + ", " + running + ")";
  $("summary").textContent =
    state.switches + " switch" + (state.switches === 1 ? "" : "es") +
    "; failed now: " + (Object.keys(state.failed).join(", ") || "nothing") +
    "; coordinator " + state.coordinator + "; robots here: " + state.here.join(", ");
  const halted = $("halted");
  halted.hidden = !state.halted;
  halted.textContent = state.halted ? "Stopped: no admissible configuration. " + state.halted : "";
  const note = $("note");
  note.hidden = state.decides;
  note.textContent = state.decides
    ? ""
    : "This page runs on " + state.here.join(", ") + ", not on the coordinator (" +
      state.coordinator + "): it shows this robot's channels and what it installs; the drawing is the first configuration " +
      "(or the last this robot coordinated, if it took over and stepped down since).";
  if (state.drawing !== page.drawing) loadDrawing(state.drawing);
  colour(state);
  robots(state);
  fallbacks(state);
}

// The "s ago" of the robots' table counts on between two updates, and after
// the page lost the run (no update comes then).
setInterval(() => {
  if (page.state) robots(page.state);
}, 1000);

function connect() {
  const status = $("connection");
  const events = new EventSource("/events");
  events.onopen = () => {
    status.textContent = "live";
    status.className = "connection on";
    page.disconnected = null;
  };
  events.onerror = () => {
    status.textContent = "disconnected: the run may have ended";
    status.className = "connection ended";
    if (page.disconnected === null) page.disconnected = Date.now() / 1000;
    if (page.state) robots(page.state);
  };
  events.onmessage = (message) => {
    const data = JSON.parse(message.data);
    if (data.state) page.state = data.state; // the entries' times are counted from its start
    if (data.entries) addEntries(data.entries);
    if (data.state) show(data.state);
  };
}

connect();
