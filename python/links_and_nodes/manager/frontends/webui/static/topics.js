// Topics: md, publishers and subscribers with their hosts, rate and bandwidth (from the
// published counter between two looks), drops of the streams between hosts; a topic's live
// decoded values through subscribe_topic.
import {el, fill, human} from './api.js';

export class Topics {
  constructor(api) {
    this.api = api;
    this.tbody = document.querySelector('#topic-table tbody');
    this.values = document.getElementById('topic-values');
    this.title = document.getElementById('topic-title');
    this.last = new Map();  // name -> {published, time}
    this.info = new Map();
    this.sub = null;
  }

  async start() {
    await this.refresh();
    setInterval(() => { if (this.visible) this.refresh().catch(() => {}); }, 2000);
  }

  shown(view) { this.visible = view === 'topics'; if (this.visible) this.refresh(); }

  async refresh() {
    if (this.busy) return;  // one look at a time: the rates pair each count with its time
    this.busy = true;
    try { await this.look(); } finally { this.busy = false; }
  }

  async look() {
    const r = await this.api.call('topics');
    const now = performance.now() / 1000;
    const rows = [];
    for (const t of r.topics) {
      let info = this.info.get(t.name);
      try {
        info = await this.api.call('topic_info', {name: t.name});
        this.info.set(t.name, info);
      } catch (e) { /* gone meanwhile */ }
      const prev = this.last.get(t.name);
      let rate = null;
      // from two looks close together (an old look would average over anything since)
      if (prev && now > prev.time && now - prev.time < 5) {
        rate = (t.published - prev.published) / (now - prev.time);
      }
      this.last.set(t.name, {published: t.published, time: now});
      const ports = (list) => (list || []).map((p) => `${p.client}@${p.host}`).join(', ');
      const drops = info ? (info.streams || []).reduce((a, s) => a + (s.drops || 0), 0) : 0;
      rows.push(el('tr', {'data-topic': t.name, onclick: () => this.open(t.name)},
        el('td', {}, t.name), el('td', {}, t.md_name),
        el('td', {}, info ? ports(info.publishers) : t.publishers),
        el('td', {}, info ? ports(info.subscribers) : t.subscribers),
        el('td', {}, rate === null ? '' : human(rate, 'Hz')),
        el('td', {}, rate === null || !info ? '' : human(rate * info.message_size, 'B/s')),
        el('td', {}, drops)));
    }
    fill(this.tbody, rows);
  }

  async open(name) {
    if (this.sub !== null) await this.api.unsubscribe(this.sub);
    this.sub = null;
    this.title.textContent = name;
    this.values.textContent = 'waiting for a sample…';
    try {
      const r = await this.api.subscribe('subscribe_topic', {name}, (ev) => {
        if (ev.event === 'error') { this.values.textContent = ev.error; return; }
        const when = new Date(ev.publish_time * 1000).toISOString();
        this.values.textContent = `seq ${ev.seq}  published ${when}\n` +
          JSON.stringify(ev.data, null, 2);
      });
      this.sub = r.sub;
    } catch (e) {
      this.values.textContent = e.message;
    }
  }
}
