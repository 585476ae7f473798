// The graph: processes (in boxes per host and .lnc group), topics, services and pull
// topics as nodes, publisher -> topic -> subscriber and caller -> service -> provider as
// edges with their rates, the .lnc dependencies as a second layer.  The `graph` command is
// asked once a second while the view is shown; the layout (dagre, fetched by the build like
// uPlot) is made again only when nodes or edges change, otherwise only the labels and states.
import {human} from './api.js';

const SVG = 'http://www.w3.org/2000/svg';
const CHAR_W = 7;        // px per character of the 12 px labels (no DOM measuring: fast)
const LINE_H = 15;
const BIG = 400;         // nodes: above it no boxes, no room for edge labels, fast layout
const PAGES = {process: 'output', topic: 'topics', service: 'services'};

function svg(tag, attrs = {}, text) {
  const node = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function rate(value, unit) {
  return value === null || value === undefined ? '' : human(value, unit);
}

// the lines of a node's label: its name, then its state or rate
function nodeLines(n) {
  const lines = [n.name];
  if (n.kind === 'process' || n.kind === 'client') {
    lines.push([n.bridge && n.bridge !== 'tool' ? `[${n.bridge}]` : '', n.state]
      .filter(Boolean).join(' '));
  } else if (n.kind === 'topic') {
    lines.push([rate(n.rate_hz, 'Hz'), rate(n.bytes_per_s, 'B/s')].filter(Boolean).join(' · '));
  } else if (n.kind === 'service') {
    lines.push(rate(n.calls_per_s, 'calls/s'));
  } else if (n.kind === 'pull') {
    lines.push(`pull on ${n.host}`);
  } else if (n.kind === 'state') {
    lines.push(n.up ? 'up' : 'down');
  }
  return lines.length > 1 ? lines : [n.name, ''];  // two lines: the rates come later
}

// room for the second line as it will be once rates come
const MIN_CHARS = {topic: 22, service: 14};

function edgeText(e) {
  if (e.kind === 'depends_on') return '';
  const r = e.kind === 'provides' ? rate(e.calls_per_s, 'calls/s') : rate(e.rate_hz, 'Hz');
  const via = e.forwarded ? `${e.forwarded.transport} ${e.forwarded.src}→${e.forwarded.dst}` : '';
  return [r, via].filter(Boolean).join(' ');
}

export class Graph {
  constructor(api) {
    this.api = api;
    this.host = document.getElementById('graph-canvas');
    this.filter = document.getElementById('graph-filter');
    this.deps = document.getElementById('graph-deps');
    this.status = document.getElementById('graph-status');
    this.data = null;        // the last answer of `graph`
    this.key = '';           // what the drawn layout was made of
    this.view = {x: 0, y: 0, k: 1};
    this.timing = null;      // {layout_ms, draw_ms, nodes, edges, at}: the last layout
    this.layouts = 0;
    this.looks = 0;          // answers of `graph` taken
    this.filter.addEventListener('input', () => this.draw(true));
    this.deps.addEventListener('change', () => this.draw(true));
    document.getElementById('graph-fit').addEventListener('click', () => this.fit());
    this.panZoom();
  }

  async start() {
    setInterval(() => { if (this.visible) this.refresh().catch(() => {}); }, 1000);
  }

  shown(view) { this.visible = view === 'graph'; if (this.visible) this.refresh().catch(() => {}); }

  async refresh() {
    if (this.busy) return;
    this.busy = true;
    try {
      this.data = await this.api.call('graph', {window: 0});
      this.looks += 1;
      this.draw(false);
    } catch (e) {
      this.status.textContent = e.message;
    } finally {
      this.busy = false;
    }
  }

  // what is shown: nodes matching the filter and their neighbours; dependencies if asked
  selection() {
    const deps = this.deps.checked;
    const q = this.filter.value.trim().toLowerCase();
    const edges = this.data.edges.filter((e) => deps || e.kind !== 'depends_on');
    let nodes = this.data.nodes.filter((n) => deps || n.kind !== 'state');
    if (q) {
      const hit = new Set(nodes.filter((n) => n.name.toLowerCase().includes(q)).map((n) => n.id));
      const near = new Set(hit);
      for (const e of edges) {
        if (hit.has(e.from)) near.add(e.to);
        if (hit.has(e.to)) near.add(e.from);
      }
      nodes = nodes.filter((n) => near.has(n.id));
    }
    const ids = new Set(nodes.map((n) => n.id));
    return {nodes, edges: edges.filter((e) => ids.has(e.from) && ids.has(e.to))};
  }

  draw(force) {
    if (!this.data) return;
    if (typeof dagre === 'undefined') {  // `pip install .` of a checkout without the build
      this.status.textContent = 'the layout code (dagre) is not installed: see docs/webui.md, ' +
        '"Building: uPlot and dagre"';
      return;
    }
    const sel = this.selection();
    const key = JSON.stringify([sel.nodes.map((n) => n.id),
                                sel.edges.map((e) => [e.from, e.to, e.kind])]);
    if (force || key !== this.key) {
      this.layout(sel);
      this.key = key;
    } else {
      this.update(sel);
    }
    const span = this.data.rate_span_s;
    this.status.textContent = `${sel.nodes.length} nodes, ${sel.edges.length} edges` +
      (span === null ? ' (rates from the next look)' : '');
  }

  layout(sel) {
    const t0 = performance.now();
    const big = sel.nodes.length > BIG;
    const hosts = new Set(sel.nodes.map((n) => n.host).filter(Boolean));
    const g = new dagre.graphlib.Graph({compound: !big});
    // a big graph: fast ranking, feedback loops cut by the greedy heuristic, one ordering
    // pass instead of the crossing reduction (about a third less time for 1,200 nodes)
    g.setGraph({rankdir: 'LR', nodesep: 16, ranksep: 50, edgesep: 8, marginx: 20, marginy: 20,
                ranker: big ? 'tight-tree' : 'network-simplex',
                acyclicer: big ? 'greedy' : undefined});
    g.setDefaultEdgeLabel(() => ({}));
    const clusters = new Map();
    const cluster = (id, label, parent) => {
      if (!clusters.has(id)) {
        clusters.set(id, label);
        g.setNode(id, {});
        if (parent) g.setParent(id, parent);
      }
      return id;
    };
    for (const n of sel.nodes) {
      const lines = nodeLines(n);
      const chars = Math.max(MIN_CHARS[n.kind] || 0, ...lines.map((l) => l.length));
      const width = chars * CHAR_W + 18;
      g.setNode(n.id, {width, height: lines.length * LINE_H + 10});
      if (big || !n.host || !['process', 'client', 'pull'].includes(n.kind)) continue;
      // a box per host where there are several, within it one per .lnc group
      const host = hosts.size > 1 ? cluster(`host:${n.host}`, `host ${n.host}`) : null;
      const group = n.group ? cluster(`group:${n.host}:${n.group}`, `group ${n.group}`, host)
        : null;
      if (group || host) g.setParent(n.id, group || host);
    }
    // the .lnc dependencies are a layer drawn over the layout, never part of it
    for (const e of sel.edges) {
      if (e.kind === 'depends_on') continue;
      const text = edgeText(e);
      g.setEdge(e.from, e.to,
                big || !text ? {} : {width: text.length * 6, height: 12, labelpos: 'c'});
    }
    dagre.layout(g, {disableOptimalOrderHeuristic: big});
    const t1 = performance.now();
    this.render(g, sel, clusters);
    const t2 = performance.now();
    this.layouts += 1;
    this.timing = {layout_ms: t1 - t0, draw_ms: t2 - t1, nodes: sel.nodes.length,
                   edges: sel.edges.length, at: performance.now()};
    if (this.layouts === 1 || this.fitNext) { this.fitNext = false; this.fit(); }
  }

  render(g, sel, clusters) {
    const root = svg('g', {class: 'graph-root'});
    for (const [id, label] of clusters) {
      const c = g.node(id);
      if (!c || !c.width) continue;
      root.append(svg('rect', {class: `cluster ${id.split(':')[0]}`, x: c.x - c.width / 2,
                               y: c.y - c.height / 2, width: c.width, height: c.height, rx: 6}));
      root.append(svg('text', {class: 'cluster-label', x: c.x - c.width / 2 + 6,
                               y: c.y - c.height / 2 + 11}, label));
    }
    this.edgeLabels = new Map();
    for (const e of sel.edges) {
      const cls = `edge kind-${e.kind}${e.forwarded ? ' forwarded' : ''}`;
      const attrs = {class: cls, 'marker-end': 'url(#graph-arrow)', 'data-from': e.from,
                     'data-to': e.to, 'data-kind': e.kind};
      if (e.kind === 'depends_on') {  // a curve between the two nodes
        const a = g.node(e.from);
        const b = g.node(e.to);
        const cx = (a.x + b.x) / 2;
        const cy = Math.min(a.y, b.y) - 30 - Math.abs(a.x - b.x) / 6;
        const from = a.x < b.x ? a.x + a.width / 2 : a.x - a.width / 2;
        const to = a.x < b.x ? b.x - b.width / 2 : b.x + b.width / 2;
        root.append(svg('path', {...attrs, d: `M${from},${a.y} Q${cx},${cy} ${to},${b.y}`}));
        continue;
      }
      const mid = g.edge(e.from, e.to);
      const pts = mid.points;
      const d = pts.map((p, i) => `${i ? 'L' : 'M'}${p.x.toFixed(1)},${p.y.toFixed(1)}`)
        .join(' ');
      root.append(svg('path', {...attrs, d}));
      const at = mid.x !== undefined ? mid : pts[Math.floor(pts.length / 2)];
      const label = svg('text', {class: 'edge-label', x: at.x, y: at.y + 3,
                                 'text-anchor': 'middle'}, edgeText(e));
      this.edgeLabels.set(`${e.from}|${e.to}|${e.kind}`, label);
      root.append(label);
    }
    this.nodeEls = new Map();
    for (const n of sel.nodes) {
      const box = g.node(n.id);
      const item = svg('g', {class: this.nodeClass(n), 'data-id': n.id, 'data-kind': n.kind,
                             'data-name': n.name, 'data-state': n.state || '',
                             transform: `translate(${box.x - box.width / 2},${box.y - box.height / 2})`});
      const shape = n.kind === 'topic' ?
        svg('rect', {width: box.width, height: box.height, rx: box.height / 2}) :
        svg('rect', {width: box.width, height: box.height, rx: n.kind === 'service' ? 10 : 3});
      item.append(shape);
      nodeLines(n).forEach((line, i) => {
        item.append(svg('text', {x: box.width / 2, y: 5 + LINE_H * (i + 0.8),
                                 'text-anchor': 'middle', class: i ? 'sub' : 'name'}, line));
      });
      item.addEventListener('click', () => { if (!this.dragged) this.open(n); });
      this.nodeEls.set(n.id, item);
      root.append(item);
    }
    const defs = svg('defs');
    const marker = svg('marker', {id: 'graph-arrow', viewBox: '0 0 10 10', refX: 10, refY: 5,
                                  markerWidth: 7, markerHeight: 7, orient: 'auto'});
    marker.append(svg('path', {d: 'M0,0 L10,5 L0,10 z', class: 'arrow'}));
    defs.append(marker);
    const size = g.graph();
    this.size = {width: size.width || 1, height: size.height || 1};
    this.canvas = svg('svg', {class: 'graph-svg', width: '100%', height: '100%'});
    this.canvas.append(defs, root);
    this.root = root;
    this.host.replaceChildren(this.canvas);
    this.apply();
  }

  nodeClass(n) {
    const bridge = n.bridge && n.bridge !== 'tool' ? ' bridge' : '';
    return `gnode kind-${n.kind} state-${n.state || (n.up ? 'up' : 'none')}${bridge}`;
  }

  // the same nodes and edges: new labels and states only
  update(sel) {
    for (const n of sel.nodes) {
      const item = this.nodeEls.get(n.id);
      if (!item) continue;
      item.setAttribute('class', this.nodeClass(n));
      item.dataset.state = n.state || '';
      const texts = item.querySelectorAll('text');
      nodeLines(n).forEach((line, i) => { if (texts[i]) texts[i].textContent = line; });
    }
    for (const e of sel.edges) {
      const label = this.edgeLabels.get(`${e.from}|${e.to}|${e.kind}`);
      if (label) label.textContent = edgeText(e);
    }
  }

  open(n) {
    const page = PAGES[n.kind];
    const lnm = window.lnm;
    if (!page || !lnm.views[page]) return;
    lnm.show(page);
    lnm.views[page].open(n.name);
  }

  // ---- zoom and pan ----------------------------------------------------------------------
  apply() {
    if (this.root) {
      const {x, y, k} = this.view;
      this.root.setAttribute('transform', `translate(${x},${y}) scale(${k})`);
    }
  }

  fit() {
    if (!this.size) { this.fitNext = true; return; }
    const w = this.host.clientWidth || 800;
    const h = this.host.clientHeight || 600;
    const k = Math.min(2, w / this.size.width, h / this.size.height);
    this.view = {k, x: (w - this.size.width * k) / 2, y: (h - this.size.height * k) / 2};
    this.apply();
  }

  panZoom() {
    this.host.addEventListener('wheel', (ev) => {
      ev.preventDefault();
      const r = this.host.getBoundingClientRect();
      const px = ev.clientX - r.left;
      const py = ev.clientY - r.top;
      const f = Math.exp(-ev.deltaY * 0.0015);
      const v = this.view;
      const k = Math.min(8, Math.max(0.02, v.k * f));
      this.view = {k, x: px - (px - v.x) * (k / v.k), y: py - (py - v.y) * (k / v.k)};
      this.apply();
    }, {passive: false});
    let start = null;
    this.host.addEventListener('mousedown', (ev) => {
      start = {x: ev.clientX, y: ev.clientY, vx: this.view.x, vy: this.view.y};
      this.dragged = false;
    });
    window.addEventListener('mousemove', (ev) => {
      if (!start) return;
      const dx = ev.clientX - start.x;
      const dy = ev.clientY - start.y;
      if (Math.abs(dx) + Math.abs(dy) > 3) this.dragged = true;
      this.view = {...this.view, x: start.vx + dx, y: start.vy + dy};
      this.apply();
    });
    window.addEventListener('mouseup', () => { start = null; });
  }

  // what the tests read: the shown nodes with their states and the edges
  model() {
    if (!this.nodeEls) return null;
    const nodes = [...this.nodeEls.values()].map((g) => (
      {id: g.dataset.id, kind: g.dataset.kind, name: g.dataset.name, state: g.dataset.state}));
    const edges = [...this.root.querySelectorAll('path.edge')].map((p) => (
      {from: p.dataset.from, to: p.dataset.to, kind: p.dataset.kind}));
    return {nodes, edges, timing: this.timing};
  }
}
