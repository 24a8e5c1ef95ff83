// The VS Code side of `st lsp`: starts the language server over stdio for Structured Text files
// (.st, TwinCAT's .TcPOU/.TcGVL/.TcDUT/.TcIO) and PLCopen XML plc.xml, and restarts it on demand
// or when st.server.command changes. Everything else (diagnostics, hover, navigation, completion,
// rename, semantic tokens) is the server's.
'use strict';

const vscode = require('vscode');
const { LanguageClient } = require('vscode-languageclient/node');

const NAME = 'Structured Text Language Server';

/** @type {LanguageClient | undefined} */
let client;
/** @type {vscode.OutputChannel | undefined} */
let output;

/** The configured command, as {command, args}, with ${workspaceFolder} and a leading ~ expanded. */
function serverCommand() {
  const configured = vscode.workspace.getConfiguration('st').get('server.command');
  const argv = Array.isArray(configured) && configured.length > 0 ? configured.map(String) : ['st', 'lsp'];
  const folder = vscode.workspace.workspaceFolders && vscode.workspace.workspaceFolders[0];
  const home = process.env.HOME || process.env.USERPROFILE || '';
  const expanded = argv.map((arg) => {
    let a = folder ? arg.split('${workspaceFolder}').join(folder.uri.fsPath) : arg;
    if (home && (a === '~' || a.startsWith('~/'))) a = home + a.slice(1);
    return a;
  });
  return { command: expanded[0], args: expanded.slice(1) };
}

function createClient() {
  const { command, args } = serverCommand();
  const folder = vscode.workspace.workspaceFolders && vscode.workspace.workspaceFolders[0];
  // stdio, without `transport: TransportKind.stdio`, which would append a --stdio argument
  const executable = { command, args, options: folder ? { cwd: folder.uri.fsPath } : {} };
  const clientOptions = {
    documentSelector: [
      { scheme: 'file', language: 'structured-text' },
      { scheme: 'untitled', language: 'structured-text' },
      { scheme: 'file', pattern: '**/plc.xml' },
    ],
    synchronize: {
      // the project's other files: a change on disk changes what a name resolves to
      fileEvents: [
        vscode.workspace.createFileSystemWatcher('**/*.{st,ST,TcPOU,TcGVL,TcDUT,TcIO,plcproj}'),
        vscode.workspace.createFileSystemWatcher('**/plc.xml'),
      ],
    },
    outputChannel: output,
    traceOutputChannel: output,
  };
  // the id 'st' makes the client read the setting st.trace.server
  return new LanguageClient('st', NAME, { run: executable, debug: executable }, clientOptions);
}

async function start() {
  client = createClient();
  try {
    await client.start();
  } catch (err) {
    const { command, args } = serverCommand();
    const message = err && err.message ? err.message : String(err);
    const choice = await vscode.window.showErrorMessage(
      `Could not start the Structured Text language server (${[command, ...args].join(' ')}): ${message}. ` +
        'Is `st` installed and on PATH? The command is the setting st.server.command.',
      'Open Settings',
      'Show Output',
    );
    if (choice === 'Open Settings') {
      vscode.commands.executeCommand('workbench.action.openSettings', 'st.server.command');
    } else if (choice === 'Show Output' && output) {
      output.show(true);
    }
  }
}

async function stop() {
  const running = client;
  client = undefined;
  if (running) {
    try {
      await running.stop();
    } catch (_) {
      // a server that never started, or that died, has nothing left to stop
    }
  }
}

async function restart() {
  await stop();
  await start();
}

/** @param {vscode.ExtensionContext} context */
async function activate(context) {
  output = vscode.window.createOutputChannel(NAME);
  context.subscriptions.push(
    output,
    vscode.commands.registerCommand('st.restartServer', restart),
    vscode.commands.registerCommand('st.showOutput', () => output && output.show(true)),
    vscode.workspace.onDidChangeConfiguration((e) => {
      if (e.affectsConfiguration('st.server.command')) restart();
    }),
  );
  await start();
}

function deactivate() {
  return stop();
}

module.exports = { activate, deactivate };
