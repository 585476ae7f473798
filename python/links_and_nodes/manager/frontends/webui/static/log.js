// The manager's own log messages, live through subscribe_log.
import {el} from './api.js';

export class Log {
  constructor(api) {
    this.api = api;
    this.pre = document.getElementById('log-lines');
  }

  async start() {
    const r = await this.api.subscribe('subscribe_log', {}, (ev) => this.add(ev));
    for (const rec of r.records) this.add(rec);
  }

  shown(view) {  // lines that came while it was hidden: show the newest
    if (view === 'log') this.pre.scrollTop = this.pre.scrollHeight;
  }

  add(rec) {
    const when = new Date(rec.time * 1000).toLocaleTimeString();
    this.pre.append(el('div', {class: `line log-${rec.level}`}, `${when} ${rec.level}: ${rec.text}`));
    while (this.pre.childElementCount > 2000) this.pre.firstChild.remove();
    this.pre.scrollTop = this.pre.scrollHeight;
  }
}
