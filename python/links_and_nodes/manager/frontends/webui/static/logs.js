// The log lines of clients (ln_log, ln.LogHandler) and of process output (log_level_regex),
// live through subscribe_logs, filtered here by level, process, host and text.
import {el} from './api.js';

const KEPT = 5000;  // lines kept in the page
const LEVELS = {debug: 10, info: 20, warning: 30, error: 40, critical: 50};

export class Logs {
  constructor(api) {
    this.api = api;
    this.lines = [];  // every entry kept, newest last (window.lnm.views.logs.lines)
    this.body = document.querySelector('#logs-table tbody');
    this.level = document.getElementById('logs-level');
    this.process = document.getElementById('logs-process');
    this.host = document.getElementById('logs-host');
    this.text = document.getElementById('logs-text');
    this.follow = document.getElementById('logs-follow');
    this.count = document.getElementById('logs-count');
    for (const input of [this.level, this.process, this.host, this.text]) {
      input.addEventListener('input', () => this.render());
      input.addEventListener('change', () => this.render());
    }
  }

  async start() {
    const r = await this.api.subscribe('subscribe_logs', {n: 1000}, (ev) => this.add(ev, true));
    for (const e of r.entries) this.add(e, false);
    this.render();
  }

  shown(view) {
    if (view === 'logs') this.scroll();
  }

  wanted(e) {
    const has = (value, filter) => !filter || (value || '').toLowerCase().includes(filter);
    return e.level >= (LEVELS[this.level.value] || 0)
      && (has(e.process, this.process.value.toLowerCase())
          || has(e.client, this.process.value.toLowerCase()))
      && has(e.host, this.host.value.toLowerCase())
      && has(e.text, this.text.value.toLowerCase());
  }

  row(e) {
    const when = new Date(e.time * 1000);
    const stamp = `${when.toLocaleTimeString([], {hour12: false})}.${String(when.getMilliseconds()).padStart(3, '0')}`;
    return el('tr', {class: `logs-${e.level_name}`, 'data-seq': e.seq},
      el('td', {}, stamp), el('td', {class: 'level'}, e.level_name),
      el('td', {}, e.process || e.client), el('td', {}, e.host),
      el('td', {}, e.file ? `${e.file.split('/').pop()}:${e.line}` : ''),
      el('td', {class: 'text'}, e.logger ? `[${e.logger}] ${e.text}` : e.text));
  }

  add(e, live) {
    this.lines.push(e);
    if (this.lines.length > KEPT) {
      this.lines.shift();
      const first = this.body.firstChild;
      if (first && Number(first.dataset.seq) < this.lines[0].seq) {
        first.remove();
      }
    }
    if (!live) return;
    if (this.wanted(e)) {
      this.body.append(this.row(e));
      this.scroll();
    }
    this.counted();
  }

  render() {
    this.body.replaceChildren(...this.lines.filter((e) => this.wanted(e)).map((e) => this.row(e)));
    this.counted();
    this.scroll();
  }

  counted() {
    this.count.textContent = `${this.body.childElementCount} of ${this.lines.length} lines`;
  }

  scroll() {
    if (this.follow.checked) this.body.parentElement.parentElement.scrollTop = 1e9;
  }
}
