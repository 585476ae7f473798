// Processes as a tree of groups: state, pid, host, restarts, reason, dependencies and what
// each waits on; start/stop/restart of a process, a group or all.  Live through
// subscribe_states; the dependency part and the resources (`top`: CPU %, RSS, threads, a
// process over its max_rss/max_cpu flagged) are refreshed every 2 s.
import {el, fill, human} from './api.js';

export class Processes {
  constructor(api) {
    this.api = api;
    this.rows = new Map();  // name -> status row
    this.tree = {groups: [], processes: []};
    this.resources = new Map();  // name -> its row of `top`
    this.tbody = document.querySelector('#process-table tbody');
    this.message = el('p', {class: 'error', id: 'process-error'});
    document.getElementById('view-processes').append(this.message);
    for (const b of document.querySelectorAll('#view-processes .toolbar button')) {
      b.addEventListener('click', () => this.act(b.dataset.action, b.dataset.target));
    }
  }

  async start() {
    const r = await this.api.subscribe('subscribe_states', {}, (ev) => {
      if (ev.process) this.rows.set(ev.name, ev.process);
      this.render();
      // what each waits on changed too: look again soon (once for a burst of transitions)
      clearTimeout(this.soon);
      this.soon = setTimeout(() => this.refreshTree().catch(() => {}), 150);
    });
    for (const p of r.processes) this.rows.set(p.name, p);
    await this.refreshTree();
    setInterval(() => this.refreshTree().catch(() => {}), 2000);
  }

  async refreshTree() {
    this.tree = await this.api.call('process_tree');
    const top = await this.api.call('top').catch(() => ({processes: []}));
    this.resources = new Map(top.processes.map((r) => [r.name, r]));
    this.render();
  }

  async act(action, target) {
    this.message.textContent = '';
    try {
      await this.api.call(action, {target});
    } catch (e) {
      this.message.textContent = `${action} ${target}: ${e.message}`;
    }
  }

  buttons(target) {
    return el('span', {class: 'actions'},
      ...['start', 'stop', 'restart'].map((a) => el('button', {
        'data-action': a, 'data-target': target, onclick: () => this.act(a, target)}, a)));
  }

  processRow(name, depth) {
    const p = this.rows.get(name) || {name, state: '?'};
    const t = this.tree.processes.find((x) => x.name === name) || {};
    const r = this.resources.get(name) || {};
    return el('tr', {'data-process': name, class: 'process'},
      el('td', {style: `padding-left:${0.6 + depth * 1.2}em`}, name),
      el('td', {class: `state state-${p.state}`}, p.state),
      el('td', {}, p.pid ?? ''), el('td', {}, p.node ?? t.node ?? ''),
      el('td', {class: 'cpu'}, r.cpu == null ? '' : r.cpu.toFixed(1)),
      el('td', {class: 'rss'}, r.rss == null ? '' : human(r.rss, 'B')),
      el('td', {class: 'threads'}, r.threads ?? ''),
      el('td', {}, p.restarts ?? ''),
      el('td', {class: r.limit ? 'reason limit' : 'reason'},
        [r.limit, p.reason].filter((x) => x).join('; ')),
      el('td', {}, (t.depends_on || []).join(', ')),
      el('td', {class: 'waiting'}, (t.waiting_on || []).join(', ')),
      el('td', {}, this.buttons(name)));
  }

  render() {
    const rows = [];
    const placed = new Set();
    const groups = new Map(this.tree.groups.map((g) => [g.name, g.members]));
    const inGroup = new Set(this.tree.groups.flatMap((g) => g.members));
    const addGroup = (name, depth) => {
      rows.push(el('tr', {class: 'group', 'data-group': name},
        el('td', {colspan: 11, style: `padding-left:${0.6 + depth * 1.2}em`}, `▾ ${name}`),
        el('td', {}, this.buttons(name))));
      for (const m of groups.get(name)) {
        if (groups.has(m)) addGroup(m, depth + 1);
        else if (!placed.has(m)) { placed.add(m); rows.push(this.processRow(m, depth + 1)); }
      }
    };
    for (const g of this.tree.groups) if (!inGroup.has(g.name)) addGroup(g.name, 0);
    for (const name of this.rows.keys()) {
      if (!placed.has(name)) rows.push(this.processRow(name, 0));
    }
    fill(this.tbody, rows);
  }
}
