#!/usr/bin/env bash
# Build the VS Code extension: install its npm packages, test the grammar, package the .vsix
# (st-iec61131-<version>.vsix here). For CI: without npm it says so and succeeds. --ignore-scripts:
# the only install script is @vscode/vsce-sign's, for signing, which packaging does not use.
set -euo pipefail
cd "$(dirname "$0")"
if ! command -v npm >/dev/null 2>&1; then
    echo "npm not found: the VS Code extension is not built"
    exit 0
fi
# @vscode/vsce 3 needs Node.js 20 or later
node_major=$(node -p 'process.versions.node.split(".")[0]' 2>/dev/null || echo 0)
if [ "$node_major" -lt 20 ]; then
    echo "Node.js $(node --version 2>/dev/null || echo missing) is older than 20: the VS Code extension is not built"
    exit 0
fi
if [ -f package-lock.json ]; then
    npm ci --no-audit --no-fund --ignore-scripts
else
    npm install --no-audit --no-fund --ignore-scripts
fi
npm test
npm run package
