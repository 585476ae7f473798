// Parameter blocks: param_blocks, param_get (the loop's current values) and param_set (an
// override), the command table's entries.
import {el, fill} from './api.js';

export class Params {
  constructor(api) {
    this.api = api;
    this.select = document.getElementById('param-block');
    this.tbody = document.querySelector('#param-table tbody');
    this.result = document.getElementById('param-result');
    this.select.addEventListener('change', () => this.load());
    document.getElementById('param-refresh').addEventListener('click', () => this.refresh());
  }

  async start() {}

  shown(view) { if (view === 'params') this.refresh(); }

  async refresh() {
    try {
      const r = await this.api.call('param_blocks');
      const chosen = this.select.value;
      this.select.replaceChildren(...r.blocks.map((b) => el('option', {value: b.id}, b.id)));
      if (chosen) this.select.value = chosen;
      await this.load();
    } catch (e) {
      this.result.textContent = e.message;
    }
  }

  async load() {
    const block = this.select.value;
    if (!block) { fill(this.tbody, []); return; }
    const r = await this.api.call('param_get', {block});
    fill(this.tbody, r.parameters.map((p) => {
      const input = el('input', {value: '', placeholder: 'JSON value'});
      const set = el('button', {onclick: () => this.set(block, p.name, input.value)}, 'Set');
      const range = p.min !== undefined || p.max !== undefined ? `${p.min ?? ''} … ${p.max ?? ''}` : '';
      return el('tr', {'data-param': p.name}, el('td', {}, p.name),
        el('td', {}, `${p.type ?? ''}${p.count > 1 ? `[${p.count}]` : ''}`),
        el('td', {}, JSON.stringify(p.value)), el('td', {}, range),
        el('td', {}, p.read_only ? 'read only' : el('span', {}, input, set)));
    }));
  }

  async set(block, name, value) {
    try {
      await this.api.call('param_set', {block, values: {[name]: value}});
      this.result.textContent = `${block}.${name} set`;
      await this.load();
    } catch (e) {
      this.result.textContent = `error: ${e.message}`;
    }
  }
}
