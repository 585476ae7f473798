// The live scope: numeric fields (array elements too) of any topics plotted with uPlot
// against their publish time.  Each topic's samples come in batches (subscribe_topic with
// "fields") into rings of CAPACITY points per signal; a requestAnimationFrame loop redraws
// when something new came.  Pause, zoom (drag; double click resets), cursor values (the
// legend), CSV and PNG export.  `buffers()`, `received`, `frames` and `latency` are read by
// the tests and the benchmark.  The pseudo topic RESOURCES offers the resource signals
// (`process/<name>/cpu`, `host/<host>/mem_used`, ...: docs/webui.md, "Resources"), read from
// `top` once per second.
import {el, download} from './api.js';

export const RESOURCES = '(resources)';

export const CAPACITY = 10000;
const COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2',
  '#17becf', '#7f7f7f', '#bcbd22'];

// A ring of doubles whose newest `n` values are always one contiguous subarray.
class Ring {
  constructor(cap) { this.cap = cap; this.a = new Float64Array(cap * 2); this.w = 0; this.n = 0; }
  push(v) {
    this.a[this.w] = v; this.a[this.w + this.cap] = v;
    this.w = (this.w + 1) % this.cap; if (this.n < this.cap) this.n++;
  }
  view() { const s = (this.w - this.n + this.cap) % this.cap; return this.a.subarray(s, s + this.n); }
  clear() { this.w = 0; this.n = 0; }
}

class Group {  // one topic's subscription: a time ring and a ring per field
  constructor(topic, fields) {
    this.topic = topic; this.fields = fields; this.sub = null;
    this.t = new Ring(CAPACITY); this.v = fields.map(() => new Ring(CAPACITY));
  }
}

export class Scope {
  constructor(api) {
    this.api = api;
    this.groups = [];
    this.paused = false;
    this.dirty = false;
    this.received = 0;
    this.frames = 0;
    this.latency = [];  // ms from publish to this page receiving the sample
    this.plot = null;
    this.$ = (id) => document.getElementById(id);
    this.$('scope-topic').addEventListener('change', () => this.loadFields());
    this.$('scope-add').addEventListener('click', () => {
      const fields = [...this.$('scope-field').selectedOptions].map((o) => o.value);
      if (fields.length) this.add(this.$('scope-topic').value, fields);
    });
    this.$('scope-clear').addEventListener('click', () => this.clear());
    this.$('scope-pause').addEventListener('click', () => this.pause(!this.paused));
    this.$('scope-csv').addEventListener('click', () => download('scope.csv', new Blob([this.csv()])));
    this.$('scope-png').addEventListener('click', () => this.png());
  }

  async start() {
    this.loop();
  }

  async shown(view) {
    if (view !== 'scope') return;
    const r = await this.api.call('topics');
    const sel = this.$('scope-topic');
    const chosen = sel.value;
    sel.replaceChildren(...r.topics.map((t) => el('option', {value: t.name}, t.name)),
      el('option', {value: RESOURCES}, RESOURCES));
    if (chosen) sel.value = chosen;
    await this.loadFields();
    this.resize();
  }

  async loadFields() {
    const name = this.$('scope-topic').value;
    if (!name) return;
    try {
      if (name === RESOURCES) {
        const top = await this.api.call('top');
        this.$('scope-field').replaceChildren(...Object.keys(top.signals).sort().map(
          (k) => el('option', {value: k}, k)));
        return;
      }
      const r = await this.api.call('topic_fields', {name});
      this.$('scope-field').replaceChildren(
        ...r.fields.map((f) => el('option', {value: f.path}, `${f.path} (${f.type})`)));
    } catch (e) {
      this.status(e.message);
    }
  }

  status(text) { this.$('scope-status').textContent = text; }

  signals() {
    return this.groups.flatMap((g) => g.fields.map((f) => ({topic: g.topic, field: f})));
  }

  async add(topic, fields) {
    const group = new Group(topic, fields);
    if (topic === RESOURCES) return this.addResources(group);
    const r = await this.api.subscribe('subscribe_topic', {name: topic, fields}, (ev) => {
      if (ev.event === 'error') { this.status(ev.error); return; }
      const now = performance.timeOrigin + performance.now();
      for (let i = 0; i < ev.t.length; i++) {
        group.t.push(ev.t[i]);
        for (let k = 0; k < fields.length; k++) group.v[k].push(Number(ev.v[k][i]));
        if (this.latency.length < 200000) this.latency.push(now - ev.t[i] * 1000);
      }
      this.received += ev.t.length;
      this.dirty = true;
    });
    group.sub = r.sub;
    this.groups.push(group);
    this.build();
    this.status(`${this.signals().length} signals`);
  }

  // Resource signals: `top` once per second; a signal without a sample is a gap.
  addResources(group) {
    const poll = async () => {
      const top = await this.api.call('top');
      group.t.push(Date.now() / 1000);
      group.fields.forEach((f, k) => group.v[k].push(top.signals[f] ?? NaN));
      this.received++;
      this.dirty = true;
    };
    group.poll = setInterval(() => poll().catch((e) => this.status(e.message)), 1000);
    this.groups.push(group);
    this.build();
    this.status(`${this.signals().length} signals`);
  }

  async clear() {
    for (const g of this.groups) {
      if (g.poll) clearInterval(g.poll);
      else await this.api.unsubscribe(g.sub);
    }
    this.groups = [];
    this.build();
  }

  pause(on) {
    this.paused = on;
    this.$('scope-pause').textContent = on ? 'Resume' : 'Pause';
  }

  // [t, v0, v1, ...] for uPlot: one topic's rings directly, several topics joined.
  data() {
    const tables = this.groups.map((g) => [g.t.view(), ...g.v.map((r) => r.view())]);
    if (tables.length === 0) return [[]];
    if (tables.length === 1) return tables[0];
    return uPlot.join(tables.map((t) => t.map((a) => Array.from(a))));
  }

  buffers() {  // for tests: plain arrays of what is plotted
    return this.groups.map((g) => ({topic: g.topic, fields: g.fields,
      t: Array.from(g.t.view()), v: g.v.map((r) => Array.from(r.view()))}));
  }

  build() {
    const box = this.$('scope-plot');
    if (this.plot) { this.plot.destroy(); this.plot = null; }
    box.replaceChildren();
    if (typeof uPlot === 'undefined') {
      box.append(el('p', {class: 'error'}, 'uPlot is missing: build with scons (it fetches it with npm)'));
      return;
    }
    const series = [{label: 'publish time', value: (u, v) => v == null ? '' : new Date(v * 1000).toISOString().slice(11, 23)}];
    this.signals().forEach((s, i) => series.push({label: `${s.topic} ${s.field}`,
      stroke: COLORS[i % COLORS.length], width: 1, points: {show: false}, spanGaps: true}));
    const opts = {width: Math.max(400, box.clientWidth || 900), height: 420, series,
      scales: {x: {time: true}}, cursor: {drag: {x: true, y: false}},
      hooks: {setSelect: [() => this.pause(true)]}};
    this.plot = new uPlot(opts, this.data(), box);
    box.ondblclick = () => this.pause(false);
    this.dirty = true;
  }

  resize() {
    const box = this.$('scope-plot');
    if (this.plot && box.clientWidth) this.plot.setSize({width: box.clientWidth, height: 420});
  }

  loop() {
    const frame = () => {
      if (this.plot && this.dirty && !this.paused) {
        this.dirty = false;
        const d = this.data();
        this.plot.setData(d, false);
        const t = d[0];
        if (t.length) {
          const win = Number(this.$('scope-window').value) || 10;
          this.plot.setScale('x', {min: t[t.length - 1] - win, max: t[t.length - 1]});
        }
        this.frames++;
      }
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  }

  csv() {
    const d = this.data();
    const head = ['publish_time', ...this.signals().map((s) => `${s.topic}:${s.field}`)];
    const lines = [head.join(',')];
    for (let i = 0; i < d[0].length; i++) {
      lines.push(d.map((col) => (col[i] ?? '')).join(','));
    }
    return lines.join('\n') + '\n';
  }

  png() {
    if (!this.plot) return;
    this.plot.ctx.canvas.toBlob((blob) => download('scope.png', blob), 'image/png');
  }
}
