// Services: the list, and a form built from the chosen service's request md that calls it
// and shows the response.
import {el, fill} from './api.js';

function inputFor(field, prefix) {
  const name = prefix + field.name;
  if (field.type === 'struct') {
    return el('fieldset', {}, el('legend', {}, field.name),
      ...field.fields.map((f) => inputFor(f, `${name}.`)));
  }
  const hint = field.kind === 'array' ? `[${field.count} × ${field.type}]` : field.type;
  return el('label', {}, `${field.name} `,
    el('input', {name, placeholder: hint, 'data-type': field.type, 'data-kind': field.kind}),
    field.doc ? el('small', {}, ` ${field.doc}`) : '');
}

function valueOf(input) {
  const text = input.value.trim();
  if (input.dataset.type === 'char') return text;
  if (text === '') return undefined;
  try { return JSON.parse(text); } catch (e) { return text; }
}

export class Services {
  constructor(api) {
    this.api = api;
    this.tbody = document.querySelector('#service-table tbody');
    this.form = document.getElementById('service-form');
    this.response = document.getElementById('service-response');
  }

  async start() { await this.refresh(); }

  shown(view) { if (view === 'services') this.refresh(); }

  async refresh() {
    const r = await this.api.call('services');
    fill(this.tbody, r.services.map((s) => el('tr', {'data-service': s.name,
      onclick: () => this.open(s.name)},
    el('td', {}, s.name), el('td', {}, s.md_name), el('td', {}, s.provider ?? s.client ?? ''))));
  }

  async open(name) {
    this.response.textContent = '';
    try {
      const form = await this.api.call('service_form', {name});
      this.form.replaceChildren(el('h3', {}, `${name} (${form.md_name})`),
        ...form.request.map((f) => inputFor(f, '')),
        el('button', {type: 'submit'}, 'Call'));
      this.form.onsubmit = (ev) => { ev.preventDefault(); this.call(name); };
    } catch (e) {
      this.form.replaceChildren(el('p', {class: 'error'}, e.message));
    }
  }

  async call(name) {
    const request = {};
    for (const input of this.form.querySelectorAll('input')) {
      const v = valueOf(input);
      if (v === undefined) continue;
      const path = input.name.split('.');
      let at = request;
      for (const p of path.slice(0, -1)) at = at[p] ??= {};
      at[path[path.length - 1]] = v;
    }
    try {
      const r = await this.api.call('service_call', {name, request});
      this.response.textContent = JSON.stringify(r.response, null, 2);
    } catch (e) {
      this.response.textContent = `error: ${e.message}`;
    }
  }
}
