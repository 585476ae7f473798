// Hosts (daemon state, host id, data port) and network statistics: topic streams between
// hosts with rates and drops, per host pair, and the pull producers' counters; the resources of
// each host (`top`: load, CPU per core, memory, network per interface).
import {el, fill, human} from './api.js';

function table(id, rows) {
  const t = document.getElementById(id);
  if (!rows.length) {  // a configuration on one host has none of these
    fill(t.tHead, []);
    fill(t.tBodies[0], [el('tr', {}, el('td', {class: 'reason'}, 'none'))]);
    return;
  }
  const keys = [...new Set(rows.flatMap((r) => Object.keys(r)))];
  const cell = (k, v) => {
    if (typeof v === 'number' && /bytes_per_s/.test(k)) return human(v, 'B/s');
    if (typeof v === 'number' && /per_s/.test(k)) return human(v, '/s');
    return typeof v === 'object' && v !== null ? JSON.stringify(v) : v;
  };
  fill(t.tHead, [el('tr', {}, ...keys.map((k) => el('th', {}, k)))]);
  fill(t.tBodies[0], rows.map((r) => el('tr', {}, ...keys.map((k) => el('td', {}, cell(k, r[k]))))));
}

export class Hosts {
  constructor(api) { this.api = api; }

  async start() {
    setInterval(() => { if (this.visible) this.refresh().catch(() => {}); }, 2000);
  }

  shown(view) { this.visible = view === 'hosts'; if (this.visible) this.refresh(); }

  async refresh() {
    const hosts = await this.api.call('hosts');
    const net = await this.api.call('network');
    table('host-table', hosts.hosts);
    table('stream-table', net.streams.concat(net.pairs.map((p) => ({pair: true, ...p}))));
    table('pull-table', net.pull || []);
    const top = await this.api.call('top');
    table('host-resources', top.hosts.map((h) => ({
      host: h.host, load: h.load.map((x) => x.toFixed(2)).join(' '), 'cpu %': h.cpu.toFixed(1),
      'per cpu %': h.cpus.map((c) => c.toFixed(0)).join(' '),
      memory: `${human(h.mem_total - h.mem_available, 'B')} of ${human(h.mem_total, 'B')}`,
      swap: `${human(h.swap_total - h.swap_free, 'B')} of ${human(h.swap_total, 'B')}`,
      network: h.nets.map((n) => `${n.interface} ↓${human(n.rx, 'B/s')} ↑${human(n.tx, 'B/s')}`)
        .join(', ')})));
  }
}
