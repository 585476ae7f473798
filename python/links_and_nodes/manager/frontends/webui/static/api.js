// The WebSocket API client: call(op, args) answers with the result object (rejects with the
// manager's error text), subscribe(op, args, onEvent) also routes the subscription's events.
// Every message carries the page's CSRF token.
export class Api {
  constructor(csrf, onStatus) {
    this.csrf = csrf;
    this.onStatus = onStatus;
    this.next = 1;
    this.waiting = new Map();
    this.handlers = new Map();
  }

  connect() {
    return new Promise((resolve, reject) => {
      const url = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`;
      this.ws = new WebSocket(url);
      this.ws.onopen = () => { this.onStatus('connected'); resolve(); };
      this.ws.onerror = () => reject(new Error('WebSocket refused'));
      this.ws.onclose = () => {
        this.onStatus('disconnected');
        for (const [, w] of this.waiting) w.reject(new Error('connection closed'));
        this.waiting.clear();
      };
      this.ws.onmessage = (msg) => this.receive(JSON.parse(msg.data));
    });
  }

  receive(data) {
    if (data.event !== undefined) {
      const handler = this.handlers.get(data.sub);
      if (handler) handler(data);
      return;
    }
    const w = this.waiting.get(data.id);
    if (!w) return;
    this.waiting.delete(data.id);
    if (data.ok) w.resolve(data); else w.reject(new Error(data.error || 'refused'));
  }

  call(op, args = {}) {
    const id = this.next++;
    return new Promise((resolve, reject) => {
      this.waiting.set(id, {resolve, reject});
      this.ws.send(JSON.stringify({id, op, ...args, csrf: this.csrf}));
    });
  }

  async subscribe(op, args, onEvent) {
    const result = await this.call(op, args);
    this.handlers.set(result.sub, onEvent);
    return result;
  }

  async unsubscribe(sub) {
    this.handlers.delete(sub);
    try { await this.call('unsubscribe', {sub}); } catch (e) { /* already gone */ }
  }
}

export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') node.className = v;
    else if (k.startsWith('on')) node.addEventListener(k.slice(2), v);
    else node.setAttribute(k, v);
  }
  for (const c of children) node.append(c instanceof Node ? c : document.createTextNode(String(c ?? '')));
  return node;
}

export function fill(tbody, rows) {
  tbody.replaceChildren(...rows);
}

export function human(n, unit) {
  if (n === null || n === undefined || Number.isNaN(n)) return '';
  const steps = ['', 'k', 'M', 'G'];
  let i = 0;
  while (Math.abs(n) >= 1000 && i < steps.length - 1) { n /= 1000; i++; }
  return `${n.toFixed(n < 10 && i ? 2 : n < 100 ? 1 : 0)} ${steps[i]}${unit}`;
}

export function download(name, blob) {
  const a = el('a', {href: URL.createObjectURL(blob), download: name});
  document.body.append(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}
