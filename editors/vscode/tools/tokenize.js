// Tokenizes a file with one of the extension's TextMate grammars, the way VS Code does
// (vscode-textmate on the Oniguruma regex engine, both devDependencies), and compiles every
// regex of both grammars first.  Prints JSON: {"regexErrors": [...], "files": {FILE:
// [[{text, scopes}, ...] for each line]}}.  Used by tests/python/editors/test_vsix.py.
// Usage: node tools/tokenize.js SCOPE FILE...   (SCOPE: source.lnc or source.lnmd)
'use strict';

const fs = require('fs');
const path = require('path');
const oniguruma = require('vscode-oniguruma');
const vsctm = require('vscode-textmate');

const SYNTAXES = path.join(__dirname, '..', 'syntaxes');
const GRAMMARS = {
  'source.lnc': path.join(SYNTAXES, 'lnc.tmLanguage.json'),
  'source.lnmd': path.join(SYNTAXES, 'lnmd.tmLanguage.json'),
};

// Every match/begin/end/while regex of a grammar, with where it is.
function* regexes(node, where) {
  if (Array.isArray(node)) {
    for (let i = 0; i < node.length; i++) yield* regexes(node[i], `${where}[${i}]`);
  } else if (node && typeof node === 'object') {
    for (const [key, value] of Object.entries(node)) {
      if (['match', 'begin', 'end', 'while'].includes(key) && typeof value === 'string') {
        yield [`${where}.${key}`, value];
      } else {
        yield* regexes(value, `${where}.${key}`);
      }
    }
  }
}

function regexErrors() {
  const errors = [];
  for (const [scope, file] of Object.entries(GRAMMARS)) {
    const grammar = JSON.parse(fs.readFileSync(file, 'utf8'));
    for (const [where, source] of regexes(grammar, scope)) {
      try {
        new oniguruma.OnigScanner([source]).dispose();
      } catch (err) {
        errors.push(`${where}: ${err.message}: ${source}`);
      }
    }
  }
  return errors;
}

async function main() {
  const [scope, ...files] = process.argv.slice(2);
  if (!GRAMMARS[scope] || !files.length) {
    console.error('usage: node tools/tokenize.js source.lnc|source.lnmd FILE...');
    process.exit(2);
  }
  const wasm = fs.readFileSync(require.resolve('vscode-oniguruma/release/onig.wasm'));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.length));
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve({
      createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
      createOnigString: (text) => new oniguruma.OnigString(text),
    }),
    loadGrammar: async (name) => GRAMMARS[name] &&
      vsctm.parseRawGrammar(fs.readFileSync(GRAMMARS[name], 'utf8'), GRAMMARS[name]),
  });
  const errors = regexErrors();
  const grammar = await registry.loadGrammar(scope);
  const out = {};
  for (const file of files) {
    let stack = vsctm.INITIAL;
    out[file] = fs.readFileSync(file, 'utf8').split(/\r?\n/).map((line) => {
      const result = grammar.tokenizeLine(line, stack);
      stack = result.ruleStack;
      return result.tokens.map((t) => ({
        text: line.slice(t.startIndex, t.endIndex), scopes: t.scopes,
      }));
    });
  }
  process.stdout.write(JSON.stringify({ regexErrors: errors, files: out }) + '\n');
}

main().catch((err) => {
  console.error(err.stack || String(err));
  process.exit(1);
});
