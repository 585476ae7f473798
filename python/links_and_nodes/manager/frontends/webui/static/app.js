// The page's entry: connects the WebSocket API, switches the views and starts each view's
// module.  window.lnm exposes the API and the views' data (the end-to-end tests read it).
import {Api} from './api.js';
import {Processes} from './processes.js';
import {Output} from './output.js';
import {Topics} from './topics.js';
import {Services} from './services.js';
import {Params} from './params.js';
import {Hosts} from './hosts.js';
import {Graph} from './graph.js';
import {Scope} from './scope.js';
import {Log} from './log.js';
import {Logs} from './logs.js';

const csrf = document.querySelector('meta[name="csrf-token"]').content;
const conn = document.getElementById('conn');
const api = new Api(csrf, (text) => { conn.textContent = text; conn.dataset.state = text; });
const lnm = {api, ready: false};
window.lnm = lnm;

function show(view) {
  for (const b of document.querySelectorAll('#tabs button')) {
    b.classList.toggle('active', b.dataset.view === view);
  }
  for (const s of document.querySelectorAll('.view')) {
    s.classList.toggle('active', s.id === `view-${view}`);
  }
  for (const v of Object.values(lnm.views)) if (v.shown) v.shown(view);
  location.hash = view;
}

async function main() {
  await api.connect();
  lnm.views = {
    processes: new Processes(api), output: new Output(api), topics: new Topics(api),
    services: new Services(api), params: new Params(api), hosts: new Hosts(api),
    scope: new Scope(api), log: new Log(api), logs: new Logs(api), graph: new Graph(api),
  };
  lnm.scope = lnm.views.scope;
  lnm.show = show;
  for (const b of document.querySelectorAll('#tabs button')) {
    b.addEventListener('click', () => show(b.dataset.view));
  }
  await Promise.all(Object.values(lnm.views).map((v) => v.start()));
  show(location.hash.slice(1) || 'processes');
  lnm.ready = true;
}

// without an auth file there is nobody to log out (the page opens a session by itself)
document.getElementById('logout').hidden =
  document.querySelector('meta[name="login"]').content !== 'password';
document.getElementById('logout').addEventListener('click', async () => {
  await fetch('/logout', {method: 'POST', headers: {'X-CSRF-Token': csrf}});
  location.href = '/';
});

main().catch((e) => { conn.textContent = `error: ${e.message}`; });
