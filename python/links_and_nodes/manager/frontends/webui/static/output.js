// Live output of one process (ANSI colours rendered, search, follow, download) and its
// state history, through subscribe_output.
import {el, download} from './api.js';

const COLORS = ['#000', '#c33', '#3a3', '#b80', '#36c', '#a3a', '#3aa', '#ccc'];
const BRIGHT = ['#666', '#f55', '#5d5', '#ed4', '#59f', '#d6d', '#5dd', '#fff'];

// One line with SGR sequences -> spans (other escape sequences are dropped).
export function ansi(text) {
  const out = document.createDocumentFragment();
  let style = {};
  const parts = text.split(/\x1b\[([0-9;]*)([A-Za-z])/);
  for (let i = 0; i < parts.length; i += 3) {
    if (parts[i]) {
      const span = el('span', {}, parts[i]);
      if (style.color) span.style.color = style.color;
      if (style.bg) span.style.background = style.bg;
      if (style.bold) span.style.fontWeight = 'bold';
      out.append(span);
    }
    if (parts[i + 2] !== 'm') continue;
    const codes = (parts[i + 1] || '0').split(';').map(Number);
    for (const c of codes) {
      if (c === 0) style = {};
      else if (c === 1) style.bold = true;
      else if (c >= 30 && c <= 37) style.color = COLORS[c - 30];
      else if (c >= 90 && c <= 97) style.color = BRIGHT[c - 90];
      else if (c >= 40 && c <= 47) style.bg = COLORS[c - 40];
      else if (c === 39) delete style.color;
      else if (c === 49) delete style.bg;
    }
  }
  return out;
}

export class Output {
  constructor(api) {
    this.api = api;
    this.lines = [];
    this.sub = null;
    this.select = document.getElementById('output-process');
    this.pre = document.getElementById('output-lines');
    this.search = document.getElementById('output-search');
    this.follow = document.getElementById('output-follow');
    this.history = document.getElementById('output-history');
    this.select.addEventListener('change', () => this.open(this.select.value));
    this.search.addEventListener('input', () => this.redraw());
    document.getElementById('output-download').addEventListener('click', () => {
      const text = this.lines.map((l) => l.text).join('\n') + '\n';
      download(`${this.select.value.replaceAll('/', '_')}.log`, new Blob([text]));
    });
  }

  async start() {
    const r = await this.api.call('status');
    this.select.replaceChildren(...r.processes.map((p) => el('option', {value: p.name}, p.name)));
    this.states = await this.api.subscribe('subscribe_states', {}, (ev) => {
      if (ev.name === this.select.value) this.addTransition(ev.transition);
    });
  }

  shown(view) {
    if (view === 'output' && this.sub === null && this.select.value) this.open(this.select.value);
  }

  async open(name) {
    if (this.sub !== null) await this.api.unsubscribe(this.sub);
    this.select.value = name;
    this.lines = [];
    const r = await this.api.subscribe('subscribe_output', {name, n: 5000}, (ev) => {
      this.lines.push(ev.line);
      if (this.lines.length > 20000) this.lines.splice(0, this.lines.length - 20000);
      this.append(ev.line);
    });
    this.sub = r.sub;
    this.lines.push(...r.lines);
    this.history.replaceChildren();
    for (const t of r.transitions) this.addTransition(t);
    this.redraw();
  }

  addTransition(t) {
    const when = new Date(t.time * 1000).toLocaleTimeString();
    this.history.append(el('li', {}, `${when} ${t.state}${t.reason ? ` — ${t.reason}` : ''}`));
  }

  matches(line) {
    const q = this.search.value;
    return !q || line.text.toLowerCase().includes(q.toLowerCase());
  }

  lineNode(line) {
    return el('div', {class: `line ${line.stream}`}, ansi(line.text));
  }

  append(line) {
    if (!this.matches(line)) return;
    this.pre.append(this.lineNode(line));
    while (this.pre.childElementCount > 5000) this.pre.firstChild.remove();
    if (this.follow.checked) this.pre.scrollTop = this.pre.scrollHeight;
  }

  redraw() {
    const shown = this.lines.filter((l) => this.matches(l)).slice(-5000);
    this.pre.replaceChildren(...shown.map((l) => this.lineNode(l)));
    if (this.follow.checked) this.pre.scrollTop = this.pre.scrollHeight;
  }
}
