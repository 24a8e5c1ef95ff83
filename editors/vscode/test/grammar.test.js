// The TextMate grammar compiles (every regex, with the Oniguruma that VS Code uses) and tokenizes
// Structured Text as intended; the language configuration's regexes are valid JavaScript and fold
// and indent the usual lines. Run with `npm test` (node's test runner).
'use strict';

const test = require('node:test');
const assert = require('node:assert');
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const oniguruma = require('vscode-oniguruma');
const vsctm = require('vscode-textmate');

const root = path.join(__dirname, '..');
const manifest = JSON.parse(fs.readFileSync(path.join(root, 'package.json'), 'utf8'));
const grammarPath = path.join(root, manifest.contributes.grammars[0].path);
const rawGrammar = JSON.parse(fs.readFileSync(grammarPath, 'utf8'));
const languageConfig = JSON.parse(fs.readFileSync(path.join(root, 'language-configuration.json'), 'utf8'));

const onigReady = (async () => {
  const wasm = fs.readFileSync(require.resolve('vscode-oniguruma/release/onig.wasm'));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.byteLength));
  return {
    createOnigScanner: (sources) => new oniguruma.OnigScanner(sources),
    createOnigString: (s) => new oniguruma.OnigString(s),
  };
})();

const registry = new vsctm.Registry({
  onigLib: onigReady,
  // source.c (an OpenPLC {{ … }} block) is VS Code's; without it the block is just not coloured
  loadGrammar: async (scopeName) =>
    scopeName === 'source.st' ? vsctm.parseRawGrammar(JSON.stringify(rawGrammar), grammarPath) : null,
});

/** Tokenize `text`: a list of lines, each a list of {text, scopes}. */
async function tokenize(text) {
  const grammar = await registry.loadGrammar('source.st');
  assert.ok(grammar, 'the grammar source.st did not load');
  let state = vsctm.INITIAL;
  return text.split('\n').map((line) => {
    const r = grammar.tokenizeLine(line, state);
    state = r.ruleStack;
    return r.tokens.map((t) => ({ text: line.slice(t.startIndex, t.endIndex), scopes: t.scopes }));
  });
}

function show(lines, lineNo) {
  return lines[lineNo].map((t) => `    ${JSON.stringify(t.text)}: ${t.scopes.slice(1).join(' ')}`).join('\n');
}

/**
 * Assert that the token `fragment` on line `lineNo` (the `nth` token of that text) carries `scope`
 * (a scope name, or a prefix of one ending in '.'); on failure the message shows the whole line's tokens.
 */
function expectScope(lines, lineNo, fragment, scope, nth = 0) {
  const found = lines[lineNo].filter((t) => t.text === fragment || t.text.trim() === fragment);
  const where = `line ${lineNo + 1} ${JSON.stringify(fragment)}`;
  if (found.length <= nth) {
    assert.fail(`${where}: no such token (expected it to be ${scope}); the line's tokens:\n${show(lines, lineNo)}`);
  }
  const scopes = found[nth].scopes;
  const ok = scopes.some((s) => (scope.endsWith('.') ? s.startsWith(scope) : s === scope));
  if (!ok) {
    assert.fail(`${where}: expected scope ${scope}, got [${scopes.join(', ')}]; the line's tokens:\n${show(lines, lineNo)}`);
  }
}

function expectNoScope(lines, lineNo, fragment, prefix) {
  const found = lines[lineNo].filter((t) => t.text === fragment || t.text.trim() === fragment);
  for (const t of found) {
    const bad = t.scopes.find((s) => s.startsWith(prefix));
    if (bad) assert.fail(`line ${lineNo + 1} ${JSON.stringify(fragment)}: unexpected scope ${bad}; tokens:\n${show(lines, lineNo)}`);
  }
}

const SAMPLE = [
  /*  1 */ "{attribute 'qualified_only'}",
  /*  2 */ 'TYPE E_Mode : (IDLE, RUN := 5); END_TYPE',
  /*  3 */ 'function_block FB_Motor EXTENDS FB_Base IMPLEMENTS I_Motor, I_Axis',
  /*  4 */ 'VAR_INPUT',
  /*  5 */ '  bStart AT %IX0.0 : BOOL; // the start button',
  /*  6 */ '  delay : TIME := T#1s500ms;',
  /*  7 */ '  pNext : POINTER TO FB_Motor;',
  /*  8 */ '  aTimers : ARRAY[1..4] OF TON;',
  /*  9 */ 'END_VAR',
  /* 10 */ "  (* nested (* comment *) still comment *) sMsg := 'it$'s $N$0D';",
  /* 11 */ '  wMsg := "wide $0041"; x := 16#FF + 2#1010 + INT#5 + 1.5E3 + 8#17;',
  /* 12 */ '  IF NOT bStart AND_THEN x MOD 2 = 0 THEN tmr(IN := TRUE, PT := TIME#2m, Q => bDone); END_IF',
  /* 13 */ '  dt1 := DT#2024-01-31-12:00:00; d := D#2024-01-31; tod1 := TOD#08:30:00; %QW3 := w.%X3;',
  /* 14 */ '  THIS^.pNext := __NEW(FB_Motor); b := E_Mode#RUN; r := INT_TO_REAL(i); rt(CLK := b);',
  /* 15 */ '  /* slash star */ %MD10 := ADR(x); y := BYTE#16#0F; ok := BOOL#TRUE;',
  /* 16 */ 'END_FUNCTION_BLOCK',
  /* 17 */ 'METHOD PUBLIC Start : BOOL',
  /* 18 */ 'FUNCTION Scale : LREAL',
  /* 19 */ 'PROGRAM Main',
  /* 20 */ '  VAR t : TON; c : CTUD; trig : R_TRIG; s : STRING(80); fb : FB_Motor; END_VAR',
  /* 21 */ '  FOR i := 1 TO 10 BY 2 DO CASE i OF 1: x := 0; ELSE x := 1; END_CASE END_FOR',
  /* 22 */ '  {IF defined (SIM)} x := 1; {END_IF}',
  /* 23 */ '  fb.Set := 1; step := step + 1;',
  /* 24 */ 'END_PROGRAM',
].join('\n');

test('the grammar and the language configuration are what scripts/generate.py writes', (t) => {
  const run = spawnSync('python3', [path.join(root, 'scripts', 'generate.py'), '--check'], { encoding: 'utf8' });
  if (run.error && run.error.code === 'ENOENT') {
    t.skip('python3 not found');
    return;
  }
  assert.strictEqual(run.status, 0, `${run.stdout}${run.stderr}`);
});

test('every regex of the grammar compiles with Oniguruma', async () => {
  await onigReady;
  const bad = [];
  (function walk(node, where) {
    if (Array.isArray(node)) return node.forEach((n, i) => walk(n, `${where}[${i}]`));
    if (node && typeof node === 'object') {
      for (const [k, v] of Object.entries(node)) {
        if (['match', 'begin', 'end', 'while'].includes(k) && typeof v === 'string') {
          try {
            new oniguruma.OnigScanner([v]).dispose();
          } catch (e) {
            bad.push(`${where}.${k}: ${e.message}\n      ${v}`);
          }
        } else {
          walk(v, `${where}.${k}`);
        }
      }
    }
  })(rawGrammar, 'grammar');
  assert.deepStrictEqual(bad, [], `regexes that do not compile:\n  ${bad.join('\n  ')}`);
  for (const [name, rule] of Object.entries(rawGrammar.repository)) {
    assert.ok(rule.match || rule.begin || rule.patterns || rule.include, `repository rule ${name} is empty`);
  }
});

test('every #include names a rule of the repository', () => {
  const missing = [];
  JSON.stringify(rawGrammar, (k, v) => {
    if (k === 'include' && v.startsWith('#') && !(v.slice(1) in rawGrammar.repository)) missing.push(v);
    return v;
  });
  assert.deepStrictEqual(missing, []);
});

test('the manifest and the grammar agree', () => {
  assert.strictEqual(rawGrammar.scopeName, 'source.st');
  assert.strictEqual(manifest.contributes.grammars[0].scopeName, 'source.st');
  const lang = manifest.contributes.languages[0];
  assert.strictEqual(lang.id, 'structured-text');
  assert.deepStrictEqual(lang.extensions, ['.st', '.TcPOU', '.TcGVL', '.TcDUT', '.TcIO']);
  assert.ok(fs.existsSync(path.join(root, lang.configuration)));
  assert.deepStrictEqual(manifest.contributes.configuration.properties['st.server.command'].default, ['st', 'lsp']);
  assert.ok(fs.existsSync(path.join(root, manifest.main)));
});

test('keywords (case-insensitive), POU names and inheritance', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 2, 'function_block', 'storage.type.pou.st');
  expectScope(l, 2, 'FB_Motor', 'entity.name.type.class.st');
  expectScope(l, 2, 'EXTENDS', 'storage.modifier.extends.st');
  expectScope(l, 2, 'FB_Base', 'entity.other.inherited-class.st');
  expectScope(l, 2, 'IMPLEMENTS', 'storage.modifier.implements.st');
  expectScope(l, 3, 'VAR_INPUT', 'storage.type.var.st');
  expectScope(l, 8, 'END_VAR', 'storage.type.var.st');
  expectScope(l, 11, 'IF', 'keyword.control.conditional.st');
  expectScope(l, 11, 'THEN', 'keyword.control.conditional.st');
  expectScope(l, 11, 'END_IF', 'keyword.control.conditional.st');
  expectScope(l, 11, 'NOT', 'keyword.operator.logical.st');
  expectScope(l, 11, 'AND_THEN', 'keyword.operator.logical.st');
  expectScope(l, 11, 'MOD', 'keyword.operator.arithmetic.st');
  expectScope(l, 13, 'THIS', 'variable.language.st');
  expectScope(l, 13, '__NEW', 'keyword.other.intrinsic.st');
  expectScope(l, 15, 'END_FUNCTION_BLOCK', 'storage.type.pou.st');
  expectScope(l, 16, 'METHOD', 'storage.type.pou.st');
  expectScope(l, 16, 'PUBLIC', 'storage.modifier.st');
  expectScope(l, 16, 'Start', 'entity.name.function.st');
  expectScope(l, 17, 'Scale', 'entity.name.function.st');
  expectScope(l, 18, 'Main', 'entity.name.type.program.st');
  expectScope(l, 20, 'FOR', 'keyword.control.loop.st');
  expectScope(l, 20, 'BY', 'keyword.control.loop.st');
  expectScope(l, 20, 'CASE', 'keyword.control.conditional.st');
  expectScope(l, 20, 'END_FOR', 'keyword.control.loop.st');
  expectScope(l, 6, 'POINTER TO', 'storage.type.reference.st');
  expectScope(l, 7, 'ARRAY', 'storage.type.reference.st');
  expectScope(l, 1, 'TYPE', 'storage.type.st');
  expectScope(l, 1, 'E_Mode', 'entity.name.type.st');
  // soft keywords used as names stay names
  expectNoScope(l, 22, 'Set', 'storage.');
  expectNoScope(l, 22, 'step', 'keyword.');
});

test('types: elementary, standard blocks, user types in declarations', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 4, 'BOOL', 'support.type.primitive.st');
  expectScope(l, 5, 'TIME', 'support.type.primitive.st');
  expectScope(l, 17, 'LREAL', 'support.type.primitive.st');
  expectScope(l, 16, 'BOOL', 'support.type.primitive.st');
  expectScope(l, 19, 'STRING', 'support.type.primitive.st');
  expectScope(l, 7, 'TON', 'support.class.st');
  expectScope(l, 19, 'TON', 'support.class.st');
  expectScope(l, 19, 'CTUD', 'support.class.st');
  expectScope(l, 19, 'R_TRIG', 'support.class.st');
  expectScope(l, 6, 'FB_Motor', 'entity.name.type.st');
  expectScope(l, 19, 'FB_Motor', 'entity.name.type.st');
  expectScope(l, 4, 'bStart', 'variable.other.declaration.st');
  expectScope(l, 13, 'INT_TO_REAL', 'support.function.conversion.st');
  expectScope(l, 14, 'ADR', 'support.function.intrinsic.st');
});

test('literals: typed, based, real, time and date, enumeration values', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 5, 'T#1s500ms', 'constant.numeric.time.st');
  expectScope(l, 11, 'TIME#2m', 'constant.numeric.time.st');
  expectScope(l, 12, 'DT#2024-01-31-12:00:00', 'constant.numeric.date-and-time.st');
  expectScope(l, 12, 'D#2024-01-31', 'constant.numeric.date.st');
  expectScope(l, 12, 'TOD#08:30:00', 'constant.numeric.time-of-day.st');
  expectScope(l, 10, '16#FF', 'constant.numeric.integer.hexadecimal.st');
  expectScope(l, 10, '2#1010', 'constant.numeric.integer.binary.st');
  expectScope(l, 10, '8#17', 'constant.numeric.integer.octal.st');
  expectScope(l, 10, 'INT', 'support.type.primitive.st');
  expectScope(l, 10, '5', 'constant.numeric.integer.decimal.st');
  expectScope(l, 10, '1.5E3', 'constant.numeric.float.st');
  expectScope(l, 14, 'BYTE', 'support.type.primitive.st');
  expectScope(l, 14, '16#0F', 'constant.numeric.integer.hexadecimal.st');
  expectScope(l, 14, 'TRUE', 'constant.language.boolean.st');
  expectScope(l, 11, 'TRUE', 'constant.language.boolean.st');
  expectScope(l, 13, 'E_Mode', 'entity.name.type.enum.st');
  expectScope(l, 13, 'RUN', 'variable.other.enummember.st');
});

test('comments: (* *) nesting, //, /* */', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 9, 'still comment', 'comment.block.st');
  expectScope(l, 9, 'comment', 'comment.block.st');
  expectScope(l, 9, 'sMsg', 'source.st'); // after the outer *): code again
  expectNoScope(l, 9, 'sMsg', 'comment');
  expectScope(l, 4, 'the start button', 'comment.line.double-slash.st');
  expectScope(l, 14, 'slash star', 'comment.block.st');
});

test('strings with $ escapes', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 9, 'it', 'string.quoted.single.st');
  expectScope(l, 9, "$'", 'constant.character.escape.st');
  expectScope(l, 9, '$N', 'constant.character.escape.st');
  expectScope(l, 9, '$0D', 'constant.character.escape.st');
  expectScope(l, 10, 'wide ', 'string.quoted.double.st');
  expectScope(l, 10, '$0041', 'constant.character.escape.st');
});

test('direct addresses, operators, pragmas', async () => {
  const l = await tokenize(SAMPLE);
  expectScope(l, 4, '%IX0.0', 'constant.other.address.st');
  expectScope(l, 12, '%QW3', 'constant.other.address.st');
  expectScope(l, 14, '%MD10', 'constant.other.address.st');
  expectScope(l, 12, '%X3', 'constant.other.address.partial.st');
  expectScope(l, 4, 'AT', 'storage.modifier.st');
  expectScope(l, 9, ':=', 'keyword.operator.assignment.st');
  expectScope(l, 11, '=>', 'keyword.operator.output.st');
  expectScope(l, 11, '=', 'keyword.operator.comparison.st');
  expectScope(l, 7, '..', 'keyword.operator.range.st');
  expectScope(l, 13, '^', 'keyword.operator.dereference.st');
  expectScope(l, 0, '{', 'meta.preprocessor.pragma.st');
  expectScope(l, 0, 'attribute', 'keyword.control.directive.pragma.st');
  expectScope(l, 0, "qualified_only", 'string.quoted.single.st');
  expectScope(l, 0, "qualified_only", 'meta.preprocessor.pragma.st');
  expectScope(l, 21, 'IF', 'keyword.control.directive.pragma.st');
  expectScope(l, 21, 'defined', 'keyword.operator.pragma.st');
});

test("TwinCAT's XML files: tags and CDATA around the ST", async () => {
  const l = await tokenize(
    [
      '<?xml version="1.0" encoding="utf-8"?>',
      '<TcPlcObject Version="1.1.0.1" ProductVersion="3.1.4024.12">',
      '  <POU Name="FB_Lamp" Id="{8d5c1b2e-0000-0000-0000-000000000000}" SpecialFunc="None">',
      '    <Declaration><![CDATA[FUNCTION_BLOCK FB_Lamp',
      'VAR_INPUT',
      '  bOn : BOOL;',
      'END_VAR]]></Declaration>',
      '    <Implementation>',
      '      <ST><![CDATA[IF bOn THEN nCount := nCount + 1; END_IF]]></ST>',
      '    </Implementation>',
      '  </POU>',
    ].join('\n'),
  );
  expectScope(l, 0, '<?xml version="1.0" encoding="utf-8"?>', 'meta.tag.preprocessor.xml.st');
  expectScope(l, 2, 'POU', 'entity.name.tag.xml.st');
  expectScope(l, 2, 'Id', 'entity.other.attribute-name.xml.st');
  expectNoScope(l, 2, '{8d5c1b2e-0000-0000-0000-000000000000}', 'meta.preprocessor');
  expectScope(l, 3, '<![CDATA[', 'punctuation.definition.cdata.begin.xml.st');
  expectScope(l, 3, 'FUNCTION_BLOCK', 'storage.type.pou.st');
  expectScope(l, 3, 'FB_Lamp', 'entity.name.type.class.st');
  expectScope(l, 5, 'BOOL', 'support.type.primitive.st');
  expectScope(l, 6, ']]>', 'punctuation.definition.cdata.end.xml.st');
  expectScope(l, 6, 'Declaration', 'entity.name.tag.xml.st');
  expectScope(l, 8, 'IF', 'keyword.control.conditional.st');
  expectScope(l, 8, 'ST', 'entity.name.tag.xml.st', 1);
});

test('language configuration: the folding and indentation regexes', () => {
  const m = languageConfig.folding.markers;
  // VS Code joins the two markers into one regex without flags: so does this test
  const fold = new RegExp(`(${m.start})|(?:${m.end})`);
  const kind = (line) => {
    const r = line.match(fold);
    return r ? (r[1] !== undefined ? 'start' : 'end') : '-';
  };
  const cases = {
    'PROGRAM Main': 'start',
    '  function_block FB_X EXTENDS FB_Y': 'start',
    '    if a THEN': 'start',
    '    IF a THEN b := 1; END_IF': '-',
    '    END_IF': 'end',
    '  var_input': 'start',
    '  END_VAR': 'end',
    '  STEP s1:': 'start',
    '  step := step + 1;': '-',
    '  step : INT;': '-',
    '{region "I/O"}': 'start',
    '{endregion}': 'end',
    'x := 1;': '-',
  };
  const wrong = Object.entries(cases)
    .filter(([line, want]) => kind(line) !== want)
    .map(([line, want]) => `${JSON.stringify(line)}: ${kind(line)}, expected ${want}`);
  assert.deepStrictEqual(wrong, [], `folding markers:\n  ${wrong.join('\n  ')}`);

  const rules = languageConfig.indentationRules;
  const inc = new RegExp(rules.increaseIndentPattern.pattern, rules.increaseIndentPattern.flags);
  const dec = new RegExp(rules.decreaseIndentPattern.pattern, rules.decreaseIndentPattern.flags);
  for (const line of ['IF a THEN', 'FOR i := 1 TO 2 DO', 'CASE x OF', 'VAR_INPUT', 'METHOD M : BOOL', 'ELSE']) {
    assert.ok(inc.test(line), `increaseIndentPattern should match ${JSON.stringify(line)}`);
  }
  for (const line of ['x := 1;', 'IF a THEN b; END_IF', 'END_IF']) {
    assert.ok(!inc.test(line), `increaseIndentPattern should not match ${JSON.stringify(line)}`);
  }
  for (const line of ['END_IF;', 'ELSIF b THEN', 'ELSE', 'UNTIL x > 3', 'end_var']) {
    assert.ok(dec.test(line), `decreaseIndentPattern should match ${JSON.stringify(line)}`);
  }
});
