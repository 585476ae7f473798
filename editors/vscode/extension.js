// The Links and Nodes extension: starts the language server ln_lsp for .lnc files and
// message definitions (docs/editors.md), hands it the `ln.*` settings, and opens files
// without an extension below a message definition directory as message definitions.
'use strict';

const path = require('path');
const vscode = require('vscode');
const { LanguageClient, TransportKind } = require('vscode-languageclient/node');

const LANGUAGES = ['lnc', 'lnmd'];
// Folders that hold message definitions by the project's conventions (docs/editors.md).
const MD_FOLDERS = ['message_definitions', 'service_definitions'];
// Files without an extension that are never message definitions.
const NOT_MD = new Set(['SConscript', 'SConstruct', 'Makefile', 'Dockerfile', 'README',
  'LICENSE', 'COPYING', 'CMakeLists', 'Jenkinsfile']);

let client = null;
let output = null;

function workspaceDir() {
  const folders = vscode.workspace.workspaceFolders;
  return folders && folders.length ? folders[0].uri.fsPath : process.cwd();
}

// The settings as ln_lsp reads them (python/links_and_nodes/manager/frontends/lsp/settings.py):
// {defines: ["A=1"], strict, shellTimeout, mdDirs: [absolute paths]}.
function serverSettings() {
  const config = vscode.workspace.getConfiguration('ln');
  const base = workspaceDir();
  return {
    defines: config.get('defines', []),
    strict: config.get('strict', false),
    shellTimeout: config.get('shellTimeout', 2),
    mdDirs: config.get('mdDirs', []).map((dir) => path.resolve(base, dir)),
  };
}

function isMessageDefinition(document) {
  if (document.uri.scheme !== 'file' || document.languageId !== 'plaintext') {
    return false;
  }
  const file = document.uri.fsPath;
  const name = path.basename(file);
  if (name.includes('.') || NOT_MD.has(name) || !/^[A-Za-z_][A-Za-z0-9_]*$/.test(name)) {
    return false;
  }
  const parts = file.split(path.sep);
  if (MD_FOLDERS.some((folder) => parts.slice(0, -1).includes(folder))) {
    return true;
  }
  return serverSettings().mdDirs.some((dir) => file.startsWith(dir + path.sep));
}

async function startClient() {
  if (client) {
    return;
  }
  const command = vscode.workspace.getConfiguration('ln').get('server.path', 'ln_lsp');
  const serverOptions = { command, args: [], transport: TransportKind.stdio };
  const clientOptions = {
    documentSelector: LANGUAGES.flatMap((language) => [
      { scheme: 'file', language },
      { scheme: 'untitled', language },
    ]),
    initializationOptions: serverSettings(),
    outputChannel: output,
  };
  client = new LanguageClient('ln', 'Links and Nodes', serverOptions, clientOptions);
  try {
    await client.start();
  } catch (err) {
    client = null;
    vscode.window.showErrorMessage(
      `Links and Nodes: cannot start the language server '${command}' (${err.message}). ` +
      'Install links_and_nodes or set "ln.server.path".');
  }
}

async function stopClient() {
  if (client) {
    const running = client;
    client = null;
    await running.stop();
  }
}

// Start the server once a document of ours is open; mark message definitions first.
function onOpen(document) {
  if (isMessageDefinition(document)) {
    vscode.languages.setTextDocumentLanguage(document, 'lnmd');
    return;
  }
  if (LANGUAGES.includes(document.languageId)) {
    startClient();
  }
}

function onConfiguration(event) {
  if (event.affectsConfiguration('ln.server.path')) {
    stopClient().then(() => vscode.workspace.textDocuments.forEach(onOpen));
  } else if (event.affectsConfiguration('ln') && client) {
    client.sendNotification('workspace/didChangeConfiguration', { settings: serverSettings() });
  }
}

function activate(context) {
  output = vscode.window.createOutputChannel('Links and Nodes');
  context.subscriptions.push(
    output,
    vscode.workspace.onDidOpenTextDocument(onOpen),
    vscode.workspace.onDidChangeConfiguration(onConfiguration),
    vscode.commands.registerCommand('ln.restartServer', async () => {
      await stopClient();
      vscode.workspace.textDocuments.forEach(onOpen);
    }),
  );
  vscode.workspace.textDocuments.forEach(onOpen);
}

function deactivate() {
  return stopClient();
}

module.exports = { activate, deactivate, isMessageDefinition };
