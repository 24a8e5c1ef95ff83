// st online mode: the browser page.
// Contract: GET api/program (static description, once), WebSocket `ws` (snapshots at 10 Hz,
// commands with results). Plain ES2020, no framework, no build step; charts with uPlot.
//
// Structure:
//   util         small DOM and formatting helpers
//   model        the program description: instances, variables, path resolution
//   conn         WebSocket: connect/reconnect, send commands, dispatch messages
//   history      ring buffer of numeric values per path (trends, motion)
//   header       state badge, control buttons, fault banner, clock, connection indicator
//   tree         instance tree (built once), selection sends `view`
//   code         ST tokenizer, code view built once per view change, value badges updated in place
//   watch        watch list (localStorage), write/force/unforce, output-force confirmation
//   trends       one uPlot chart of the ticked variables over a sliding window
//   tasks        per-task statistics tables and histograms
//   motion, ethercat, modbus   optional views
//   log, toast, confirm        messages
//   render loop  one requestAnimationFrame per snapshot; only the visible view is updated
'use strict';
(() => {
  // ------------------------------------------------------------------ util
  const $ = (id) => document.getElementById(id);

  function h(tag, props, ...kids) {
    const e = document.createElement(tag);
    if (props) {
      for (const [k, v] of Object.entries(props)) {
        if (v == null || v === false) continue;
        if (k === 'class') e.className = v;
        else if (k === 'text') e.textContent = v;
        else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
        else e.setAttribute(k, v === true ? '' : v);
      }
    }
    for (const c of kids.flat()) if (c != null && c !== false) e.append(c);
    return e;
  }

  /** Set text only when it changed (cheap in-place update). */
  function setText(e, text) {
    if (e._text !== text) { e.textContent = text; e._text = text; }
  }

  function fmtUs(ns) {
    if (ns == null) return '–';
    const x = ns / 1000;
    if (x < 10) return x.toFixed(2);
    if (x < 1000) return x.toFixed(1);
    return Math.round(x).toLocaleString('en-US');
  }

  /** A REAL as its literal writes it: a fraction always (40.0, 1.5, 1.0E30). */
  function realText(x) {
    if (!Number.isFinite(x)) return String(x);
    const s = String(+x.toPrecision(7));
    if (/e/i.test(s)) { const [m, e] = s.split(/e/i); return (m.includes('.') ? m : m + '.0') + 'E' + (+e); }
    return s.includes('.') ? s : s + '.0';
  }

  /** A log axis's tick in µs, short: 0.5, 19, 310, 1.2k, 79k. */
  function fmtTick(v) {
    if (v == null) return '';
    if (v < 10) return String(+v.toFixed(1));
    if (v < 1000) return String(Math.round(v));
    return (v < 10000 ? +(v / 1000).toFixed(1) : Math.round(v / 1000)) + 'k';
  }

  function fmtSec(ns) { return (ns / 1e9).toFixed(1) + ' s'; }

  function fmtInterval(ns) {
    if (ns >= 1e9 && ns % 1e9 === 0) return ns / 1e9 + ' s';
    if (ns >= 1e6) return +(ns / 1e6).toFixed(3) + ' ms';
    return +(ns / 1e3).toFixed(3) + ' µs';
  }

  function fmtNum(x) {
    if (x == null || Number.isNaN(x)) return '–';
    const a = Math.abs(x);
    if (a !== 0 && (a >= 1e6 || a < 1e-3)) return x.toExponential(3);
    return (+x.toFixed(3)).toString();
  }

  const COLORS = ['#1f6fd1', '#d62728', '#2ca02c', '#9467bd', '#e07b00', '#17a2b8',
    '#8c564b', '#d63384', '#6c757d', '#a0a000'];

  function store(key, value) {
    try { localStorage.setItem(key, JSON.stringify(value)); } catch (_) { /* private mode */ }
  }
  function load(key) {
    try { return JSON.parse(localStorage.getItem(key) || 'null'); } catch (_) { return null; }
  }

  // ------------------------------------------------------------------ state
  const S = {
    prog: null,
    inst: new Map(),       // path -> instance node
    instLower: new Map(),  // lower-case path -> instance node
    varMaps: new Map(),    // pou name -> Map(lower-case name -> var)
    viewed: null,          // instance path shown in the Code view
    tab: 'code',
    watch: [],             // watched paths
    trend: new Set(),      // watched paths ticked "Trend"
    snap: null,            // latest snapshot
    forced: new Set(),
    renderQueued: false,
  };

  // ------------------------------------------------------------------ model
  function indexInstances(nodes, parent) {
    for (const n of nodes) {
      n.parent = parent;
      S.inst.set(n.path, n);
      S.instLower.set(n.path.toLowerCase(), n);
      indexInstances(n.children || [], n);
    }
  }

  function varMap(pouName) {
    let m = S.varMaps.get(pouName);
    if (!m) {
      m = new Map();
      const pou = S.prog.pous[pouName];
      for (const v of (pou ? pou.vars : [])) m.set(v.name.toLowerCase(), v);
      S.varMaps.set(pouName, m);
    }
    return m;
  }

  /** Resolve `parts` (identifier chain) in the scope of an instance, following block instances:
   *  returns {path, v, used} (used = how many parts were resolved) or null. */
  function resolveInScope(instPath, parts) {
    const node = S.inst.get(instPath);
    if (!node) return null;
    let v = varMap(node.pou).get(parts[0].toLowerCase());
    if (!v) return null;
    let path = node.path + '.' + v.name;
    let used = 1;
    while (used < parts.length) {
      const child = S.inst.get(path);
      if (!child) break;
      const m = varMap(child.pou).get(parts[used].toLowerCase());
      if (!m) break;
      v = m; path += '.' + m.name; used++;
    }
    return { path, v, used };
  }

  /** Resolve a full path typed by the user (case-insensitive); a bare name is taken
   *  relative to the viewed instance. Returns {path, v} (v null when unknown). */
  function resolvePath(text) {
    const parts = text.trim().split('.').filter(Boolean);
    if (!parts.length) return null;
    for (let i = parts.length - 1; i >= 1; i--) {
      const node = S.instLower.get(parts.slice(0, i).join('.').toLowerCase());
      if (node) {
        const r = resolveInScope(node.path, parts.slice(i));
        if (r && r.used === parts.length - i) return { path: r.path, v: r.v };
        return { path: [node.path, ...parts.slice(i)].join('.'), v: null };
      }
    }
    if (S.viewed) {
      const r = resolveInScope(S.viewed, parts);
      if (r && r.used === parts.length) return { path: r.path, v: r.v };
    }
    return { path: parts.join('.'), v: null };
  }

  function taskOf(node) {
    for (let n = node; n; n = n.parent) if (n.task) return n.task;
    return null;
  }

  function varOf(path) {
    const i = path.lastIndexOf('.');
    if (i < 0) return null;
    const node = S.inst.get(path.slice(0, i));
    return node ? varMap(node.pou).get(path.slice(i + 1).toLowerCase()) || null : null;
  }

  function valueOf(path) {
    return S.snap && S.snap.values ? S.snap.values[path] : undefined;
  }

  // ------------------------------------------------------------------ conn
  const C = { ws: null, open: false, retry: 0, nextId: 1, pending: new Map() };

  function connect() {
    const url = new URL('ws', location.href);
    url.protocol = location.protocol === 'https:' ? 'wss:' : 'ws:';
    let ws;
    try { ws = new WebSocket(url.href); } catch (e) { scheduleReconnect(); return; }
    C.ws = ws;
    ws.onopen = () => {
      C.open = true; C.retry = 0;
      setConn(true);
      if (S.viewed) send({ type: 'view', instance: S.viewed });
      sendWatch();
    };
    ws.onmessage = (ev) => {
      let msg;
      try { msg = JSON.parse(ev.data); } catch (_) { return; }
      if (msg.type === 'snapshot') onSnapshot(msg);
      else if (msg.type === 'result') onResult(msg);
      else if (msg.type === 'program') location.reload();  // an online change: the new program (the watch list stays)
    };
    ws.onclose = (ev) => {
      if (C.ws !== ws) return;
      C.ws = null; C.open = false; C.pending.clear();
      setConn(false);
      if (ev.code === 4401 || ev.code === 4403) {
        // the server is up but does not know this page's session: the PLC (st run) was restarted,
        // with a new token, or the session ended; reconnecting cannot help, signing in does
        sessionEnded(ev.code === 4401
          ? 'The PLC was restarted, or this page\'s session ended: sign in again to go on.'
          : 'The server refused this page (another host or origin).');
        return;
      }
      scheduleReconnect();
    };
    ws.onerror = () => { /* onclose follows */ };
  }

  function scheduleReconnect() {
    const delay = Math.min(5000, 300 * 2 ** C.retry++);
    setTimeout(connect, delay);
  }

  /** Send a message; `label` names the action for error reports. Returns false when offline. */
  function send(msg, label) {
    if (!C.open) {
      if (label) toast(`${label}: not connected to the PLC`);
      return false;
    }
    const id = C.nextId++;
    C.pending.set(id, label || msg.type);
    C.ws.send(JSON.stringify({ ...msg, id }));
    return true;
  }

  function onResult(msg) {
    const label = C.pending.get(msg.id);
    C.pending.delete(msg.id);
    if (!msg.ok) toast(msg.error || `${label || 'command'} refused`);
  }

  function setConn(open) {
    const e = $('conn');
    e.textContent = open ? 'online' : 'disconnected';
    e.classList.toggle('ok', open);
    e.classList.toggle('bad', !open);
    e.title = open ? 'Connected to the PLC' : 'Connection lost; reconnecting…';
    document.body.classList.toggle('offline', !open);
    if (!open) {  // the last state seen is no longer known to hold
      const st = $('state');
      st.textContent = '?';
      st.className = 'state state-unknown';
      st.title = 'Not connected: the PLC\'s state is unknown';
      S.lastState = null;
      localLog('warning', 'connection to the PLC lost; reconnecting…');
    } else if (S.everOpen) {
      localLog('log', 'connected to the PLC again');
    }
    if (open) S.everOpen = true;
  }

  function sessionEnded(text) {
    $('session-text').textContent = text;
    $('session-banner').hidden = false;
    $('conn').textContent = 'signed out';
    localLog('error', text);
  }

  // ------------------------------------------------------------------ snapshots & render loop
  function onSnapshot(snap) {
    const prev = S.snap;
    S.snap = snap;
    S.forced = new Set(snap.forced || []);
    histPush(snap, prev);
    appendLog(snap.log || []);
    if (S.lastState && S.lastState !== snap.state) {
      localLog(snap.state === 'FAULT' ? 'error' : 'log', `state ${S.lastState} → ${snap.state}` +
        (snap.state === 'FAULT' && snap.fault ? `: ${faultText(snap.fault)}` : ''), snap.time_ns);
    }
    S.lastState = snap.state;
    // a view whose subject appeared after the program was described (axes register on first use)
    for (const [tab, on] of [['motion', snap.axes && snap.axes.length], ['ethercat', snap.ethercat], ['modbus', snap.modbus]]) {
      if (on) document.querySelector(`[data-tab="${tab}"]`).hidden = false;
    }
    if (!S.renderQueued) {
      S.renderQueued = true;
      requestAnimationFrame(render);
    }
  }

  function render() {
    S.renderQueued = false;
    const snap = S.snap;
    if (!snap) return;
    renderHeader(snap);
    const view = VIEWS[S.tab];
    if (view && view.update) view.update(snap);
  }

  // ------------------------------------------------------------------ history
  const WINDOW_MAX_S = 125;
  const Hist = { t: [], series: new Map(), names: new Map() };  // names: an enumeration's ordinal → its literal

  const ENUM_TEXT = /^[A-Za-z_]\w*#[A-Za-z_]\w*$/;
  const TIME_PREFIX = /^(T|TIME|LT|LTIME|D|DATE|LD|LDATE|TOD|TIME_OF_DAY|LTOD|DT|DATE_AND_TIME|LDT)#/i;
  function isEnumText(text) { return typeof text === 'string' && ENUM_TEXT.test(text) && !TIME_PREFIX.test(text); }

  function histKeys(snap) {
    const keys = [];
    for (const p of S.watch) keys.push([p, valueOf(p)]);
    for (const a of snap.axes || []) {
      keys.push([`axis:${a.no}:pos`, { num: a.position }]);
      keys.push([`axis:${a.no}:vel`, { num: a.velocity }]);
    }
    return keys;
  }

  function histPush(snap, prev) {
    const t = snap.time_ns / 1e9;
    const n = Hist.t.length;
    if (n && t < Hist.t[n - 1]) histClear();        // PLC time restarted (reset)
    else if (n && t === Hist.t[n - 1]) return;      // stopped: no new point
    Hist.t.push(t);
    const len = Hist.t.length;
    for (const [key, val] of histKeys(snap)) {
      let arr = Hist.series.get(key);
      if (!arr) { arr = new Array(len - 1).fill(null); Hist.series.set(key, arr); }
      const num = val && typeof val.num === 'number' ? val.num : null;
      arr.push(num);
      if (num != null && isEnumText(val.text)) {
        let names = Hist.names.get(key);
        if (!names) { names = new Map(); Hist.names.set(key, names); }
        names.set(num, val.text.slice(val.text.indexOf('#') + 1));
      }
    }
    for (const arr of Hist.series.values()) while (arr.length < len) arr.push(null);
    let drop = 0;
    while (drop < Hist.t.length && Hist.t[drop] < t - WINDOW_MAX_S) drop++;
    if (drop) {
      Hist.t.splice(0, drop);
      for (const arr of Hist.series.values()) arr.splice(0, drop);
    }
  }

  function histClear() {
    Hist.t.length = 0;
    Hist.series.clear();
    Hist.names.clear();
  }

  /** Data for uPlot: [t, ...series] over the last `win` seconds. */
  function histData(keys, win) {
    const t = Hist.t;
    const end = t.length ? t[t.length - 1] : 0;
    let lo = 0, hi = t.length;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (t[mid] < end - win) lo = mid + 1; else hi = mid; }
    const data = [t.slice(lo)];
    for (const k of keys) {
      const arr = Hist.series.get(k);
      data.push(arr ? arr.slice(lo) : new Array(t.length - lo).fill(null));
    }
    return { data, end };
  }

  function trendWindow() { return +$('trend-window').value || 30; }

  // ------------------------------------------------------------------ header
  function initHeader() {
    $('prog-name').textContent = S.prog.name;
    document.title = `${S.prog.name} — st online`;
    $('btn-start').onclick = () => send({ type: 'control', action: 'start' }, 'Run');
    $('btn-stop').onclick = () => send({ type: 'control', action: 'stop' }, 'Stop');
    $('btn-reset-warm').onclick = () => send({ type: 'control', action: 'reset_warm' }, 'Reset (warm)');
    $('btn-reset-cold').onclick = async () => {
      const ok = await confirmDialog('Cold reset',
        'Reset (cold): every variable, RETAIN ones included, returns to its initial value and the ' +
        'program restarts. Continue?', 'Reset (cold)');
      if (ok) send({ type: 'control', action: 'reset_cold' }, 'Reset (cold)');
    };
    $('fault-banner').onclick = showFaultLocation;
    $('forced-btn').onclick = () => { renderForcedList(); $('forced-dialog').showModal(); };
    $('forced-close').onclick = () => $('forced-dialog').close();
    $('unforce-all').onclick = async () => {
      const n = S.forced.size;
      if (!n) { $('forced-dialog').close(); return; }
      $('forced-dialog').close();
      const ok = await confirmDialog('Unforce all',
        `Release all ${n} forced variable${n > 1 ? 's' : ''}? The program (and the inputs) set them again from the next scan.`,
        'Unforce all');
      if (ok) send({ type: 'unforce', path: '' }, 'Unforce all');
    };
    if (S.prog.read_only) {
      document.body.classList.add('read-only');
      $('ro-badge').hidden = false;
    }
  }

  function renderHeader(snap) {
    const st = $('state');
    setText(st, snap.state);
    st.className = 'state state-' + String(snap.state).toLowerCase();
    st.title = 'The PLC\'s state';
    const n = S.forced.size;
    const fb = $('forced-btn');
    setText(fb, `${n} forced`);
    fb.classList.toggle('has-forced', n > 0);
    $('stop-banner').hidden = snap.state !== 'STOP';
    if ($('forced-dialog').open) renderForcedList();
    $('btn-start').classList.toggle('active', snap.state === 'RUN');
    $('btn-stop').classList.toggle('active', snap.state === 'STOP');
    setText($('clock'), `${fmtSec(snap.time_ns)} · ${Number(snap.scans || 0).toLocaleString('en-US')} scans`);
    const banner = $('fault-banner');
    const f = snap.state === 'FAULT' ? snap.fault : null;
    banner.hidden = !f;
    if (f) setText(banner, faultText(f));
  }

  function renderForcedList() {
    const paths = [...S.forced].sort();
    $('forced-none').hidden = paths.length > 0;
    $('unforce-all').disabled = !paths.length || document.body.classList.contains('read-only');
    $('forced-list').replaceChildren(...paths.map((p) => {
      const val = valueOf(p);
      return h('tr', { 'data-testid': 'forced-row' }, h('td', { text: p }), h('td', { text: val ? val.text : '' }),
        h('td', null, h('button', { type: 'button', text: 'Unforce', onclick: () => doUnforce(p) })));
    }));
  }

  function faultText(f) {
    const loc = f.file ? f.file + (f.line != null ? ':' + f.line : '') : null;
    const rest = [loc, f.pou && `POU ${f.pou}`, f.task && `task ${f.task}`].filter(Boolean).join(', ');
    return `FAULT ${f.kind}: ${f.message}` + (rest ? ` — ${rest}` : '');
  }

  /** Clicking the fault banner opens the faulting POU at the faulting line. */
  function showFaultLocation() {
    const f = S.snap && S.snap.fault;
    if (!f || !f.pou) return;
    let target = null;
    for (const node of S.inst.values()) {
      if (node.pou !== f.pou) continue;
      if (!target || (f.task && node.task === f.task)) target = node;
    }
    if (!target) return;
    selectInstance(target.path);
    showTab('code');
    const line = Code.lines.get(f.line);
    if (line) line.scrollIntoView({ block: 'center' });
  }

  // ------------------------------------------------------------------ tree
  function buildTree() {
    const root = $('tree');
    root.replaceChildren(h('div', { class: 'pane-title', text: 'Instances' }),
      treeList(S.prog.instances, 0));
  }

  function treeList(nodes, depth) {
    return h('ul', { role: depth ? 'group' : 'tree' }, nodes.map((n) => treeNode(n, depth)));
  }

  function treeNode(n, depth) {
    const hasKids = n.children && n.children.length > 0;
    const twisty = h('span', { class: 'twisty' + (hasKids ? '' : ' leaf'), text: hasKids ? '▾' : '' });
    const kind = n.kind === 'PROGRAM' ? 'PRG' : n.kind === 'FUNCTION_BLOCK' ? 'FB' : n.kind;
    const name = depth ? n.path.slice(n.path.lastIndexOf('.') + 1) : n.path;
    const item = h('div', {
      class: 'tree-item', 'data-testid': 'tree-item', 'data-path': n.path, role: 'treeitem',
      title: `${n.path} : ${n.pou}` + (n.task ? ` (task ${n.task})` : ''), tabindex: '0',
      style: `padding-left:${6 + depth * 14}px`,
    }, twisty, h('span', { class: 'name', text: name }), h('span', { class: 'pou', text: n.pou }),
    h('span', { class: 'kind kind-' + kind.toLowerCase(), text: kind }));
    const li = h('li', null, item, hasKids ? treeList(n.children, depth + 1) : null);
    twisty.addEventListener('click', (ev) => {
      if (!hasKids) return;
      ev.stopPropagation();
      const collapsed = li.classList.toggle('collapsed');
      twisty.textContent = collapsed ? '▸' : '▾';
    });
    item.addEventListener('click', () => { selectInstance(n.path); showTab('code'); });
    item.addEventListener('keydown', (ev) => {
      if (ev.key === 'Enter' || ev.key === ' ') { ev.preventDefault(); item.click(); }
    });
    return li;
  }

  function selectInstance(path) {
    if (!S.inst.has(path)) return;
    if (S.viewed !== path) {
      S.viewed = path;
      store(storeKey('view'), path);
      for (const e of document.querySelectorAll('.tree-item')) {
        e.classList.toggle('selected', e.dataset.path === path);
      }
      buildCodeView();
      send({ type: 'view', instance: path });
      sendWatch();
    }
    render();
  }

  // ------------------------------------------------------------------ code: tokenizer
  const KEYWORDS = new Set(('PROGRAM END_PROGRAM FUNCTION_BLOCK END_FUNCTION_BLOCK FUNCTION END_FUNCTION ' +
    'VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_GLOBAL VAR_EXTERNAL VAR_TEMP VAR_STAT VAR_ACCESS VAR_CONFIG ' +
    'END_VAR CONSTANT RETAIN NON_RETAIN PERSISTENT AT IF THEN ELSIF ELSE END_IF CASE OF END_CASE FOR TO ' +
    'BY DO END_FOR WHILE END_WHILE REPEAT UNTIL END_REPEAT EXIT CONTINUE RETURN AND AND_THEN OR OR_ELSE ' +
    'XOR NOT MOD TRUE FALSE TYPE END_TYPE STRUCT END_STRUCT ARRAY POINTER REF_TO REF DEREF NULL THIS ' +
    'SUPER METHOD END_METHOD INTERFACE END_INTERFACE PROPERTY END_PROPERTY EXTENDS IMPLEMENTS PUBLIC ' +
    'PRIVATE PROTECTED INTERNAL ABSTRACT FINAL OVERRIDE CONFIGURATION END_CONFIGURATION RESOURCE ' +
    'END_RESOURCE TASK WITH ON NAMESPACE END_NAMESPACE USING JMP').split(' '));
  const TYPES = new Set(('BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL ' +
    'LREAL TIME LTIME DATE LDATE TIME_OF_DAY TOD LTOD DATE_AND_TIME DT LDT STRING WSTRING CHAR WCHAR ' +
    'ANY ANY_NUM ANY_INT ANY_REAL ANY_BIT').split(' '));

  const isIdStart = (c) => (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c === '_';
  const isDigit = (c) => c >= '0' && c <= '9';
  const isIdChar = (c) => isIdStart(c) || isDigit(c);

  /** Split one source line into segments {t, s}; t is one of code, comment, string, kw, type,
   *  num, addr, ident (a variable candidate, dotted allowed). `st` carries the open-comment state
   *  and the parenthesis depth across lines. */
  function tokenizeLine(line, st) {
    const out = [];
    const n = line.length;
    let code = '';
    let i = 0;
    const flush = () => { if (code) { out.push({ t: 'code', s: code }); code = ''; } };
    const push = (t, s) => { flush(); out.push({ t, s }); };
    while (i < n) {
      if (st.comment) {
        const j = line.indexOf('*)', i);
        const end = j < 0 ? n : j + 2;
        push('comment', line.slice(i, end));
        if (j >= 0) st.comment = false;
        i = end;
        continue;
      }
      const c = line[i];
      const c2 = line.substr(i, 2);
      if (c2 === '(*') {
        const j = line.indexOf('*)', i + 2);
        if (j < 0) { push('comment', line.slice(i)); st.comment = true; break; }
        push('comment', line.slice(i, j + 2)); i = j + 2; continue;
      }
      if (c2 === '/*') {   // CODESYS-style block comment on one line
        const j = line.indexOf('*/', i + 2);
        const end = j < 0 ? n : j + 2;
        push('comment', line.slice(i, end)); i = end; continue;
      }
      if (c2 === '//') { push('comment', line.slice(i)); break; }
      if (c === '{') {     // pragma
        const j = line.indexOf('}', i);
        const end = j < 0 ? n : j + 1;
        push('comment', line.slice(i, end)); i = end; continue;
      }
      if (c === "'" || c === '"') {
        let j = i + 1;
        while (j < n && line[j] !== c) j += line[j] === '$' ? 2 : 1;
        const end = Math.min(j + 1, n);
        push('string', line.slice(i, end)); i = end; continue;
      }
      if (c === '%') {
        let j = i + 1;
        while (j < n && (isIdChar(line[j]) || line[j] === '.' || line[j] === '*')) j++;
        push('addr', line.slice(i, j)); i = j; continue;
      }
      if (isDigit(c)) {
        let j = i + 1;
        while (j < n && (isIdChar(line[j]) || line[j] === '#' ||
          (line[j] === '.' && isDigit(line[j + 1] || '')))) j++;
        push('num', line.slice(i, j)); i = j; continue;
      }
      if (isIdStart(c)) {
        let j = i + 1;
        while (j < n && isIdChar(line[j])) j++;
        if (line[j] === '#') {         // typed literal: T#1s, INT#5, 16#FF, Color#Red
          j++;
          if (line[j] === '-' || line[j] === '+') j++;
          while (j < n && (isIdChar(line[j]) || line[j] === '.' || line[j] === ':' ||
            (line[j] === '-' && isDigit(line[j + 1] || '')))) j++;
          push('num', line.slice(i, j)); i = j; continue;
        }
        while (line[j] === '.' && isIdStart(line[j + 1] || '')) {
          j += 2;
          while (j < n && isIdChar(line[j])) j++;
        }
        const word = line.slice(i, j);
        const up = word.toUpperCase();
        const member = i > 0 && line[i - 1] === '.';      // a[i].x: not a variable of the scope
        const formal = st.depth > 0 && /^\s*(:=|=>)/.test(line.slice(j)); // t1(IN := ...)
        if (KEYWORDS.has(up)) push('kw', word);
        else if (TYPES.has(up)) push('type', word);
        else if (member || formal) code += word;
        else push('ident', word);
        i = j;
        continue;
      }
      if (c === '(') st.depth++;
      else if (c === ')') st.depth = Math.max(0, st.depth - 1);
      else if (c === ';') st.depth = 0;
      code += c;
      i++;
    }
    flush();
    return out;
  }

  // ------------------------------------------------------------------ code: view
  const Code = {
    badges: new Map(),  // path -> [badge elements]
    lines: new Map(),   // file line number -> line element
    hit: new Set(),
    extra: [],          // badge paths that are not variables of the viewed instance itself
    pou: null,
    faultLine: null,
  };

  function makeBadge(path) {
    const b = h('span', { class: 'val', 'data-path': path, title: `${path} — click to watch` });
    let list = Code.badges.get(path);
    if (!list) { list = []; Code.badges.set(path, list); }
    list.push(b);
    return b;
  }

  function buildCodeView() {
    Code.badges.clear(); Code.lines.clear(); Code.hit.clear(); Code.faultLine = null; Code.extra = [];
    const node = S.inst.get(S.viewed);
    const head = $('code-head');
    const body = $('code-body');
    if (!node) { head.replaceChildren(); body.replaceChildren(); return; }
    const pou = S.prog.pous[node.pou] || { source: [], vars: [], file: '', first_line: 1 };
    Code.pou = node.pou;
    const task = node.task || (node.parent && taskOf(node.parent));
    head.replaceChildren(...[
      h('span', { class: 'inst', text: node.path }),
      h('span', { class: 'muted', text: ` : ${node.pou}` }),
      h('span', { class: 'kind', text: node.kind }),
      task ? h('span', { class: 'muted', text: `task ${task}` }) : null,
      pou.file ? h('span', { class: 'file', text: `${pou.file}:${pou.first_line}` }) : null,
    ].filter(Boolean));
    body.replaceChildren(pou.source && pou.source.length
      ? codeLines(node, pou) : varTable(node, pou));
    body.scrollTop = 0;
    const own = node.path.split('.').length + 1;
    Code.extra = [...Code.badges.keys()].filter((p) => p.split('.').length > own);
  }

  function codeLines(node, pou) {
    const st = { comment: false, depth: 0 };
    const frag = h('div', { class: 'code' });
    pou.source.forEach((text, k) => {
      const no = pou.first_line + k;
      const src = h('span', { class: 'src' });
      for (const seg of tokenizeLine(text, st)) src.append(...segmentNodes(node, seg));
      if (!text) src.append('\u200b');
      const line = h('div', { class: 'line', 'data-line': no }, h('span', { class: 'ln', text: String(no) }), src);
      Code.lines.set(no, line);
      frag.append(line);
    });
    return frag;
  }

  function segmentNodes(node, seg) {
    if (seg.t === 'code') return [seg.s];
    if (seg.t !== 'ident') return [h('span', { class: 'tk-' + seg.t, text: seg.s })];
    const parts = seg.s.split('.');
    const r = resolveInScope(node.path, parts);
    if (!r) return [seg.s];
    if (r.used === parts.length && r.v.elementary) {
      return [h('span', { class: 'tk-var', text: seg.s }), makeBadge(r.path)];
    }
    return [h('span', { class: 'tk-var', text: seg.s })];
  }

  function varTable(node, pou) {
    const rows = pou.vars.map((v) => h('tr', null,
      h('td', { class: 'mono', text: v.name }),
      h('td', { class: 'mono', text: v.type }),
      h('td', { class: 'muted', text: v.section + (v.location ? ` AT ${v.location}` : '') }),
      h('td', null, v.elementary ? makeBadge(node.path + '.' + v.name) : h('span', { class: 'muted', text: '(structured)' }))));
    return h('div', { class: 'libvars' },
      h('div', { class: 'hint', text: `${node.pou} is a library block: no source; its variables:` }),
      h('table', { class: 'grid vars-table' },
        h('thead', null, h('tr', null, h('th', { text: 'Name' }), h('th', { text: 'Type' }),
          h('th', { text: 'Section' }), h('th', { text: 'Value' }))),
        h('tbody', null, rows)));
  }

  function updateBadge(b, val, forced) {
    const text = val ? val.text : '…';
    if (b._text !== text) {
      b.textContent = text; b._text = text;
      b.classList.toggle('true', text === 'TRUE');
      b.classList.toggle('false', text === 'FALSE');
      b._forced = null;   // refresh the tooltip below
    }
    if (b._forced !== forced) {
      b._forced = forced;
      b.classList.toggle('forced', forced);
      b.title = `${b.dataset.path} = ${text}${forced ? ' (FORCED)' : ''} — click to watch`;
    }
  }

  function updateCode(snap) {
    for (const [path, list] of Code.badges) {
      const val = snap.values ? snap.values[path] : undefined;
      const forced = S.forced.has(path);
      for (const b of list) updateBadge(b, val, forced);
    }
    const lines = snap.lines && snap.lines.pou === Code.pou ? snap.lines.hit : [];
    const next = new Set(lines);
    for (const no of Code.hit) if (!next.has(no)) { const e = Code.lines.get(no); if (e) e.classList.remove('hit'); }
    for (const no of next) if (!Code.hit.has(no)) { const e = Code.lines.get(no); if (e) e.classList.add('hit'); }
    Code.hit = next;
    const f = snap.state === 'FAULT' && snap.fault && snap.fault.pou === Code.pou ? snap.fault.line : null;
    if (f !== Code.faultLine) {
      if (Code.faultLine != null) { const e = Code.lines.get(Code.faultLine); if (e) e.classList.remove('fault-line'); }
      if (f != null) { const e = Code.lines.get(f); if (e) e.classList.add('fault-line'); }
      Code.faultLine = f;
    }
  }

  function initCode() {
    $('code-body').addEventListener('click', (ev) => {
      const b = ev.target.closest('.val');
      if (!b) return;
      addWatch(b.dataset.path);
      b.classList.add('flash');
      setTimeout(() => b.classList.remove('flash'), 400);
    });
  }

  // ------------------------------------------------------------------ watch
  const Watch = { rows: new Map() };  // path -> {tr, value, forcedCell, input, trend}

  function storeKey(what) { return `st-online:${what}:${S.prog.name}`; }

  function saveWatch() {
    store(storeKey('watch'), { paths: S.watch, trend: [...S.trend] });
  }

  function loadWatch() {
    const saved = load(storeKey('watch'));
    if (!saved || !Array.isArray(saved.paths)) return;
    S.watch = saved.paths.filter((p) => typeof p === 'string');
    S.trend = new Set((saved.trend || []).filter((p) => S.watch.includes(p)));
  }

  /** The server sends values of the viewed instance's own variables and of watched paths; the
   *  members of block instances shown in the code view (t1.Q) are watched too, behind the scenes. */
  function sendWatch() {
    const paths = [...new Set([...S.watch, ...Code.extra])];
    send({ type: 'watch', paths });
  }

  function addWatch(text) {
    const r = resolvePath(text);
    if (!r) return;
    if (!S.watch.includes(r.path)) {
      S.watch.push(r.path);
      $('watch-body').append(watchRow(r.path));
      saveWatch();
      sendWatch();
      watchChanged();
    }
    const tab = document.querySelector('[data-tab="watch"]');
    tab.classList.remove('pulse'); void tab.offsetWidth; tab.classList.add('pulse');
  }

  function removeWatch(path) {
    S.watch = S.watch.filter((p) => p !== path);
    S.trend.delete(path);
    const row = Watch.rows.get(path);
    if (row) row.tr.remove();
    Watch.rows.delete(path);
    saveWatch();
    sendWatch();
    watchChanged();
    Trends.dirty = true;
  }

  function watchChanged() {
    $('watch-empty').hidden = S.watch.length > 0;
    setText($('watch-count'), S.watch.length ? String(S.watch.length) : '');
    render();
  }

  /** An example literal of the row's type for its New value field (the type from the program's
   *  description or, for an array element or a global, from the server). */
  function placeholderFor(type, val) {
    if (!type) return 'ST literal';
    const t = type.toUpperCase();
    if (t.startsWith('ARRAY')) return 'an element: [i]';
    if (t === 'BOOL') return 'TRUE / FALSE';
    if (t === 'TIME' || t === 'LTIME') return 'T#1s500ms';
    if (t === 'TOD' || t === 'TIME_OF_DAY') return 'TOD#12:00:00';
    if (t === 'DATE') return 'D#2024-01-31';
    if (t === 'DT' || t === 'DATE_AND_TIME') return 'DT#2024-01-31-12:00:00';
    if (t.includes('REAL')) return '1.5';
    if (t.includes('STRING')) return "'text'";
    if (/^(U?[SDL]?INT|BYTE|L?D?WORD)$/.test(t)) return '42';
    if (val && val.text && val.text.includes('#')) return val.text;  // an enumeration: Type#Member
    return 'ST literal';
  }

  function watchRow(path) {
    const v = varOf(path);
    const value = h('span', { class: 'value', text: '…' });
    const forcedCell = h('td', { class: 'c-forced' });
    const input = h('input', {
      type: 'text', class: 'new-value', 'data-testid': 'new-value', spellcheck: 'false',
      placeholder: placeholderFor(v && v.type), 'aria-label': `New value for ${path}`,
    });
    const trend = h('input', { type: 'checkbox', class: 'trend', 'data-testid': 'trend-check', title: 'Show in Trends' });
    trend.checked = S.trend.has(path);
    const btn = (testid, text, title, fn, cls) => h('button', { type: 'button', 'data-testid': testid, class: cls, title, text, onclick: fn });
    const tr = h('tr', { 'data-testid': 'watch-row', 'data-path': path },
      h('td', { class: 'c-path' }, h('span', { class: 'path', text: path }),
        v && v.location ? h('span', { class: 'addr' + (v.output ? ' out' : ''), text: v.location }) : null),
      h('td', { class: 'c-type', 'data-testid': 'watch-type', text: v ? v.type : '' }),
      h('td', { class: 'c-value' }, value),
      forcedCell,
      h('td', { class: 'c-new change' }, input),
      h('td', { class: 'c-actions change' },
        btn('btn-write', 'Write', 'Write the value once', () => doWrite(path, input)),
        btn('btn-force', 'Force', 'Force the value (held every scan)', () => doForce(path, input), 'force'),
        btn('btn-unforce', 'Unforce', 'Release the forced value', () => doUnforce(path))),
      h('td', { class: 'c-trend' }, trend),
      h('td', { class: 'c-remove' }, btn('btn-remove', '✕', `Remove ${path} from the watch list`, () => removeWatch(path), 'remove')));
    input.addEventListener('keydown', (ev) => { if (ev.key === 'Enter') doWrite(path, input); });
    trend.addEventListener('change', () => {
      if (trend.checked) S.trend.add(path); else S.trend.delete(path);
      saveWatch();
      Trends.dirty = true;
    });
    Watch.rows.set(path, { tr, value, forcedCell, input, forced: null, typeCell: tr.querySelector('.c-type'), seen: false });
    return tr;
  }

  function buildWatch() {
    Watch.rows.clear();
    $('watch-body').replaceChildren(...S.watch.map(watchRow));
    watchChanged();
  }

  function updateWatch(snap) {
    for (const [path, row] of [...Watch.rows]) {
      const val = snap.values ? snap.values[path] : undefined;
      if (val && val.error) {
        if (!row.seen) {  // never had a value: the path is not the program's
          removeWatch(path);
          toast(`Not watched: ${val.error}`);
          continue;
        }
        val.text = `(${val.error})`;
      } else if (val) {
        row.seen = true;
        if (val.type && !row.typeCell.textContent) {
          row.typeCell.textContent = val.type;
          row.input.placeholder = placeholderFor(val.type, val);
        } else if (val.type && row.input.placeholder === 'ST literal') {
          row.input.placeholder = placeholderFor(val.type, val);
        }
      }
      const text = val ? val.text : '…';
      if (row.value._text !== text) {
        row.value.textContent = text; row.value._text = text;
        row.value.classList.toggle('true', text === 'TRUE');
        row.value.classList.toggle('false', text === 'FALSE');
        row.value.title = text;
      }
      const forced = S.forced.has(path);
      if (row.forced !== forced) {
        row.forced = forced;
        row.tr.classList.toggle('is-forced', forced);
        row.tr.classList.toggle('not-forced', !forced);
        row.forcedCell.replaceChildren(forced ? h('span', { class: 'forced', text: 'FORCED' }) : '');
      }
    }
  }

  function typedValue(path, input) {
    const value = input.value.trim();
    if (!value) { toast(`${path}: type a value first`); input.focus(); return null; }
    return value;
  }

  function doWrite(path, input) {
    const value = typedValue(path, input);
    if (value != null) send({ type: 'write', path, value }, `Write ${path}`);
  }

  async function doForce(path, input) {
    const value = typedValue(path, input);
    if (value == null) return;
    const v = varOf(path);
    if (v && v.output) {
      const ok = await confirmDialog('Force an output',
        `Force output ${path} (${v.location}) to ${value}? The physical output follows the forced ` +
        'value whatever the program does, until it is unforced.', 'Force output');
      if (!ok) return;
    }
    send({ type: 'force', path, value }, `Force ${path}`);
  }

  function doUnforce(path) { send({ type: 'unforce', path }, `Unforce ${path}`); }

  function initWatch() {
    $('watch-add').addEventListener('submit', (ev) => {
      ev.preventDefault();
      const input = $('watch-add-input');
      if (input.value.trim()) addWatch(input.value);
      input.value = '';
    });
  }

  // ------------------------------------------------------------------ charts (uPlot helpers)
  const AXIS = { stroke: '#555', grid: { stroke: '#eceff3', width: 1 }, ticks: { stroke: '#d6dae0', width: 1 }, font: '11px system-ui, sans-serif' };

  // a y axis as wide as its longest label (uPlot calls it with the labels it will draw)
  function labelSize(u, values) {
    if (!values || !values.length) return 40;
    return Math.max(40, Math.max(...values.map((v) => String(v).length)) * 7 + 16);
  }

  function chartSize(box, height) {
    return { width: Math.max(200, box.clientWidth), height };
  }

  function observeSize(box, getChart, height) {
    const ro = new ResizeObserver(() => {
      const c = getChart();
      if (c && box.clientWidth > 0) c.setSize(chartSize(box, typeof height === 'function' ? height() : height));
    });
    ro.observe(box);
  }

  // ------------------------------------------------------------------ trends
  const Trends = { chart: null, keys: [], dirty: true };

  function trendHeight() {
    const box = $('trend-chart');
    return Math.max(160, box.clientHeight - 40);
  }

  function buildTrendChart() {
    const box = $('trend-chart');
    if (Trends.chart) { Trends.chart.destroy(); Trends.chart = null; }
    Trends.keys = S.watch.filter((p) => S.trend.has(p));
    Trends.dirty = false;
    $('trend-hint').textContent = Trends.keys.length
      ? 'BOOL variables on the right axis (0/1).'
      : 'Tick "Trend" in the Watch tab to chart variables.';
    box.replaceChildren();
    if (!Trends.keys.length) return;
    const isBool = (p) => { const v = varOf(p); return v ? v.type.toUpperCase() === 'BOOL' : false; };
    const anyBool = Trends.keys.some(isBool);
    const anyNum = Trends.keys.some((p) => !isBool(p));
    const series = [{ label: 't', value: (u, v) => (v == null ? '–' : v.toFixed(1) + ' s') }];
    const typeOf = (p) => { const v = varOf(p); const val = valueOf(p); return ((v && v.type) || (val && val.type) || '').toUpperCase(); };
    Trends.keys.forEach((p, k) => {
      const b = isBool(p);
      const t = typeOf(p);
      const timeLike = /^(L?TIME|L?TOD|TIME_OF_DAY|LTIME_OF_DAY)$/.test(t);  // charted in ms
      const val = valueOf(p);
      const enumLike = Hist.names.has(p) || (val && isEnumText(val.text));  // its ordinal; the name on hover
      let fmt = (u, v) => fmtNum(v);
      if (t.includes('REAL')) fmt = (u, v) => (v == null ? '–' : realText(v));  // 40.0, as the IEC literal
      if (b) fmt = (u, v) => (v == null ? '–' : v ? 'TRUE' : 'FALSE');
      else if (timeLike) fmt = (u, v) => (v == null ? '–' : fmtNum(v) + ' ms');
      else if (enumLike) fmt = (u, v) => { const n = Hist.names.get(p); return v == null ? '–' : (n && n.get(v)) || String(v); };
      series.push({
        label: p + (timeLike ? ' (ms)' : ''), stroke: COLORS[k % COLORS.length], width: 1.5, scale: b ? 'bool' : 'y',
        paths: b || enumLike ? uPlot.paths.stepped({ align: 1 }) : undefined, points: { show: false },
        value: fmt,
      });
    });
    const axes = [{ ...AXIS, values: (u, ticks) => ticks.map((v) => +v.toFixed(1) + ' s') }];
    if (anyNum) axes.push({ ...AXIS, scale: 'y', size: labelSize });
    if (anyBool) {
      axes.push({ ...AXIS, scale: 'bool', side: anyNum ? 1 : 3, size: 50, grid: { show: !anyNum },
        splits: () => [0, 1], values: (u, ticks) => ticks.map((v) => (v === 1 ? 'TRUE' : v === 0 ? 'FALSE' : '')) });
    }
    Trends.chart = new uPlot({
      ...chartSize(box, trendHeight()),
      scales: {
        x: { time: false, range: () => { const e = Hist.t.length ? Hist.t[Hist.t.length - 1] : 0; return [e - trendWindow(), e]; } },
        y: { auto: true },
        bool: { auto: false, range: [-0.1, 1.1] },
      },
      series, axes,
      cursor: { drag: { x: false, y: false } },
      legend: { live: true },
    }, histData(Trends.keys, trendWindow()).data, box);
  }

  function updateTrends() {
    if (Trends.dirty || (!Trends.chart && Trends.keys.length)) buildTrendChart();
    if (!Trends.chart) return;
    const { data } = histData(Trends.keys, trendWindow());
    const u = Trends.chart;
    u.setData(data);
    // Without the cursor on the chart, the legend shows the newest values.
    if (u.cursor.left == null || u.cursor.left < 0) u.setLegend({ idx: data[0].length - 1 });
  }

  function initTrends() {
    $('trend-window').addEventListener('change', () => { if (Trends.chart) updateTrends(); });
    observeSize($('trend-chart'), () => Trends.chart, trendHeight);
  }

  // ------------------------------------------------------------------ tasks
  const Tasks = { sig: '', cards: new Map() };

  function taskCard(desc) {
    const cell = (k) => h('td', { 'data-k': k, class: 'num' });
    const instances = [...S.inst.values()].filter((n) => n.task === desc.name).map((n) => n.path);
    const statRow = (label, prefix, keys) => h('tr', null, h('th', { text: label }),
      ['min', 'mean', 'p99', 'max', 'last'].map((k) => (keys.includes(k) ? cell(prefix + k) : h('td', { class: 'num muted', text: '' }))));
    const histBox = (kind, title) => h('div', { class: 'hist' },
      h('div', { class: 'hist-title', text: title }), h('div', { class: 'chart-box', 'data-h': kind }));
    const card = h('div', { class: 'card task-card', 'data-task': desc.name },
      h('h3', null, h('span', { text: desc.name }),
        h('span', { class: 'muted', text: (desc.interval_ns ? `every ${fmtInterval(desc.interval_ns)}` : 'event/continuous') +
          ` · priority ${desc.priority}` + (instances.length ? ` · ${instances.join(', ')}` : '') })),
      h('div', { class: 'task-tables' },
        h('table', { class: 'grid counters' },
          h('tbody', null,
            h('tr', null, h('th', { text: 'Jobs' }), cell('jobs')),
            h('tr', null, h('th', { text: 'Overruns' }), cell('overruns')),
            h('tr', null, h('th', { text: 'Skipped' }), cell('skipped')),
            h('tr', null, h('th', { text: '(m,k)' }), cell('mk')),
            h('tr', null, h('th', { text: 'Utility' }), cell('utility')))),
        h('table', { class: 'grid times' },
          h('thead', null, h('tr', null, h('th', { text: 'µs' }),
            ['min', 'mean', 'p99', 'max', 'last'].map((k) => h('th', { class: 'num', text: k })))),
          h('tbody', null,
            statRow('Latency', 'lat_', ['min', 'mean', 'p99', 'max', 'last']),
            statRow('Execution', 'exec_', ['min', 'mean', 'p99', 'max', 'last'])))),
      h('div', { class: 'hists' }, histBox('exec', 'Execution time (µs)'), histBox('latency', 'Latency (µs)')));
    const cells = {};
    for (const td of card.querySelectorAll('[data-k]')) cells[td.dataset.k] = td;
    return { card, cells, charts: {}, sig: {} };
  }

  function buildTasks(snap) {
    const body = $('tasks-body');
    for (const t of Tasks.cards.values()) for (const c of Object.values(t.charts)) c.destroy();
    Tasks.cards.clear();
    body.replaceChildren();
    const descs = new Map((S.prog.tasks || []).map((t) => [t.name, t]));
    for (const t of snap.tasks || []) {
      const c = taskCard(descs.get(t.name) || { name: t.name, interval_ns: 0, priority: '?' });
      Tasks.cards.set(t.name, c);
      body.append(c.card);
    }
  }

  function histChart(box, edges, color) {
    const opts = {
      ...chartSize(box, 150),
      legend: { show: false },
      cursor: { drag: { x: false, y: false }, points: { show: false } },
      // the bins are four per octave: a log x axis gives each its width, so one far spike does not
      // squash the rest into one bar
      scales: { x: { time: false, distr: 3, log: 2, range: [Math.max(edges[0], 1) / 1000, edges[edges.length - 1] / 1000] }, y: { range: (u, lo, hi) => [0, Math.max(1, hi * 1.05)] } },
      axes: [{ ...AXIS, values: (u, ticks) => ticks.map(fmtTick) }, { ...AXIS, size: labelSize }],
      series: [{}, { label: 'count', fill: color + '99', stroke: color, width: 1, paths: uPlot.paths.bars({ size: [0.92, 80], align: 0 }), points: { show: false } }],
    };
    const chart = new uPlot(opts, [[], []], box);
    observeSize(box, () => (box.isConnected ? chart : null), 150);
    return chart;
  }

  function histData2(hist) {
    const e = hist.edges_ns;
    const xs = hist.counts.map((_, i) => (e[i] + e[i + 1]) / 2000);
    return [xs, hist.counts.slice()];
  }

  function updateTaskCard(c, t) {
    const set = (k, text) => setText(c.cells[k], text);
    set('jobs', Number(t.jobs).toLocaleString('en-US'));
    set('overruns', String(t.overruns));
    c.cells.overruns.classList.toggle('warn', t.overruns > 0);
    set('skipped', String(t.skipped));
    c.cells.skipped.classList.toggle('warn', t.skipped > 0);
    if (t.mk) {
      set('mk', `${t.mk.m} of ${t.mk.k} met`);
      c.cells.mk.classList.toggle('bad', !t.mk.met);
      set('utility', t.mk.utility == null ? '–' : (+t.mk.utility).toFixed(3));
    } else { set('mk', '–'); set('utility', '–'); }
    const lat = t.latency_ns || {}, ex = t.exec_ns || {};
    for (const k of ['min', 'mean', 'p99', 'max', 'last']) set('lat_' + k, fmtUs(lat[k]));
    for (const k of ['min', 'mean', 'p99', 'max', 'last']) set('exec_' + k, fmtUs(ex[k]));
    for (const [kind, color] of [['exec', '#1f6fd1'], ['latency', '#e07b00']]) {
      const hist = t.hist && t.hist[kind];
      if (!hist || !hist.counts || !hist.counts.length) continue;
      const sig = hist.edges_ns.join(',');
      if (c.sig[kind] !== sig) {
        if (c.charts[kind]) c.charts[kind].destroy();
        const box = c.card.querySelector(`[data-h="${kind}"]`);
        box.replaceChildren();
        c.charts[kind] = histChart(box, hist.edges_ns, color);
        c.sig[kind] = sig;
      }
      c.charts[kind].setData(histData2(hist));
    }
  }

  function updateTasks(snap) {
    const sig = (snap.tasks || []).map((t) => t.name).join('|');
    if (sig !== Tasks.sig) { buildTasks(snap); Tasks.sig = sig; }
    for (const t of snap.tasks || []) {
      const c = Tasks.cards.get(t.name);
      if (c) updateTaskCard(c, t);
    }
  }

  // ------------------------------------------------------------------ motion
  const Motion = { sig: '', cards: new Map() };

  function axisChart(box, key, label, color) {
    const chart = new uPlot({
      ...chartSize(box, 120),
      legend: { show: false },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false, range: () => { const e = Hist.t.length ? Hist.t[Hist.t.length - 1] : 0; return [e - trendWindow(), e]; } } },
      axes: [{ ...AXIS, values: (u, ticks) => ticks.map((v) => +v.toFixed(1) + ' s') }, { ...AXIS, size: labelSize }],
      series: [{}, { label, stroke: color, width: 1.5, points: { show: false } }],
    }, histData([key], trendWindow()).data, box);
    observeSize(box, () => (box.isConnected ? chart : null), 120);
    return chart;
  }

  function axisCard(no) {
    const f = (k, label) => h('div', { class: 'kv' }, h('span', { class: 'k', text: label }), h('span', { class: 'v', 'data-k': k }));
    const posBox = h('div', { class: 'chart-box' });
    const velBox = h('div', { class: 'chart-box' });
    const card = h('div', { class: 'card axis-card', 'data-axis': no },
      h('h3', null, h('span', { text: `Axis ${no}` }), h('span', { class: 'axis-state', 'data-k': 'state' })),
      h('div', { class: 'kvs' }, f('position', 'Position'), f('velocity', 'Velocity'), f('error', 'Last error')),
      h('div', { class: 'axis-charts' },
        h('div', null, h('div', { class: 'hist-title', text: 'Position' }), posBox),
        h('div', null, h('div', { class: 'hist-title', text: 'Velocity' }), velBox)));
    const cells = {};
    for (const e of card.querySelectorAll('[data-k]')) cells[e.dataset.k] = e;
    return { card, cells, posBox, velBox, charts: null };
  }

  function updateMotion(snap) {
    const axes = snap.axes || [];
    const sig = axes.map((a) => a.no).join('|');
    if (sig !== Motion.sig) {
      for (const c of Motion.cards.values()) if (c.charts) c.charts.forEach((x) => x.destroy());
      Motion.cards.clear();
      const body = $('motion-body');
      body.replaceChildren();
      for (const a of axes) { const c = axisCard(a.no); Motion.cards.set(a.no, c); body.append(c.card); }
      Motion.sig = sig;
    }
    for (const a of axes) {
      const c = Motion.cards.get(a.no);
      setText(c.cells.state, a.state);
      c.cells.state.classList.toggle('bad', !!a.error || /error/i.test(a.state));
      setText(c.cells.position, fmtNum(a.position));
      setText(c.cells.velocity, fmtNum(a.velocity));
      setText(c.cells.error, a.error || a.error_id ? `${a.error_id} (16#${Number(a.error_id).toString(16).toUpperCase()}) ${a.error_text || ''}` : 'none');
      c.cells.error.classList.toggle('bad', !!a.error);
      if (!c.charts) {
        c.charts = [axisChart(c.posBox, `axis:${a.no}:pos`, 'position', '#1f6fd1'),
          axisChart(c.velBox, `axis:${a.no}:vel`, 'velocity', '#2ca02c')];
      } else {
        c.charts[0].setData(histData([`axis:${a.no}:pos`], trendWindow()).data);
        c.charts[1].setData(histData([`axis:${a.no}:vel`], trendWindow()).data);
      }
    }
  }

  // ------------------------------------------------------------------ ethercat, modbus
  const Keyed = { ecat: new Map(), modbus: new Map() };

  /** Update a keyed table in place: rows added/removed as keys come and go. */
  function syncRows(tbody, map, items, keyOf, cellsOf) {
    const seen = new Set();
    for (const it of items) {
      const key = keyOf(it);
      seen.add(key);
      const texts = cellsOf(it);
      let row = map.get(key);
      if (!row) {
        const tds = texts.map(() => h('td'));
        row = { tr: h('tr', { 'data-key': key }, tds), tds };
        map.set(key, row);
      }
      tbody.append(row.tr);  // keeps order; no-op move when already in place
      texts.forEach((t, k) => {
        const [text, cls] = Array.isArray(t) ? t : [t, ''];
        setText(row.tds[k], String(text));
        if (row.tds[k]._cls !== cls) { row.tds[k].className = cls; row.tds[k]._cls = cls; }
      });
    }
    for (const [key, row] of map) if (!seen.has(key)) { row.tr.remove(); map.delete(key); }
  }

  function updateEthercat(snap) {
    const e = snap.ethercat;
    if (!e) { setText($('ecat-summary'), 'EtherCAT not active.'); return; }
    setText($('ecat-summary'), `Lost frames: ${e.lost_frames} · WKC errors: ${e.wkc_errors} · Slaves: ${(e.slaves || []).length}`);
    $('ecat-summary').classList.toggle('warn', e.lost_frames > 0 || e.wkc_errors > 0);
    syncRows($('ecat-body'), Keyed.ecat, e.slaves || [], (s) => s.position, (s) => [
      [s.position, 'num'], s.name, [s.state, s.state === 'OP' ? 'ok' : 'bad'], [s.wkc_errors ?? '—', s.wkc_errors ? 'num warn' : 'num']]);
  }

  function updateModbus(snap) {
    const clients = (snap.modbus && snap.modbus.clients) || [];
    $('modbus-empty').hidden = clients.length > 0;
    syncRows($('modbus-body'), Keyed.modbus, clients, (c) => c.peer, (c) => [[c.peer, 'mono'], [c.requests, 'num']]);
  }

  // ------------------------------------------------------------------ log
  const LOG_MAX = 200;

  /** A line of the page's own (a state change, the connection) in the log, at the PLC time it saw. */
  function localLog(kind, text, timeNs) {
    const t = timeNs != null ? timeNs : (S.snap ? S.snap.time_ns : null);
    appendLog([{ time_ns: t, kind, text }]);
  }

  function appendLog(entries) {
    if (!entries.length) return;
    const empty = $('log-empty');
    if (empty) empty.remove();
    const log = $('log');
    const atBottom = log.scrollHeight - log.scrollTop - log.clientHeight < 30;
    const frag = document.createDocumentFragment();
    for (const m of entries) {
      frag.append(h('div', { class: `log-line kind-${m.kind}` },
        h('span', { class: 't', text: m.time_ns != null ? (m.time_ns / 1e9).toFixed(3) : '' }),
        h('span', { class: 'k', text: m.kind }),
        h('span', { class: 'msg', text: m.text })));
    }
    log.append(frag);
    while (log.children.length > LOG_MAX) log.firstElementChild.remove();
    if (atBottom) log.scrollTop = log.scrollHeight;
  }

  // ------------------------------------------------------------------ toast, confirm
  let toastTimer = null;
  function toast(text) {
    const t = $('toast');
    t.textContent = text;
    t.hidden = false;
    clearTimeout(toastTimer);
    toastTimer = setTimeout(() => { t.hidden = true; }, 6000);
  }

  function confirmDialog(title, text, yesLabel) {
    const dlg = $('confirm-dialog');
    $('confirm-title').textContent = title;
    $('confirm-text').textContent = text;
    $('confirm-yes').textContent = yesLabel || 'Confirm';
    dlg.returnValue = '';
    return new Promise((resolve) => {
      dlg.addEventListener('close', () => resolve(dlg.returnValue === 'yes'), { once: true });
      dlg.showModal();
      $('confirm-no').focus();
    });
  }

  // ------------------------------------------------------------------ tabs
  const VIEWS = {
    code: { update: updateCode },
    watch: { update: updateWatch },
    trends: { update: updateTrends },
    tasks: { update: updateTasks },
    motion: { update: updateMotion },
    ethercat: { update: updateEthercat },
    modbus: { update: updateModbus },
  };

  function showTab(name) {
    if (!VIEWS[name]) return;
    S.tab = name;
    for (const b of document.querySelectorAll('#tabs [data-tab]')) {
      const on = b.dataset.tab === name;
      b.classList.toggle('active', on);
      b.setAttribute('aria-selected', on ? 'true' : 'false');
    }
    for (const v of document.querySelectorAll('#views .view')) v.hidden = v.dataset.view !== name;
    render();
  }

  function initTabs() {
    const p = S.prog;
    document.querySelector('[data-tab="motion"]').hidden = !(p.axes && p.axes.length);
    document.querySelector('[data-tab="ethercat"]').hidden = !p.ethercat;
    document.querySelector('[data-tab="modbus"]').hidden = !p.modbus;
    $('tabs').addEventListener('click', (ev) => {
      const b = ev.target.closest('[data-tab]');
      if (b) showTab(b.dataset.tab);
    });
  }

  // ------------------------------------------------------------------ start
  async function loadProgram() {
    for (let attempt = 0; ; attempt++) {
      try {
        const r = await fetch('api/program', { cache: 'no-store', credentials: 'same-origin' });
        if (!r.ok) throw new Error(`api/program: HTTP ${r.status}`);
        return await r.json();
      } catch (e) {
        setConn(false);
        if (attempt === 0) toast(`Cannot load the program description (${e.message}); retrying…`);
        await new Promise((res) => setTimeout(res, Math.min(5000, 500 * 2 ** attempt)));
      }
    }
  }

  async function start() {
    S.prog = await loadProgram();
    indexInstances(S.prog.instances || [], null);
    initHeader();
    initTabs();
    buildTree();
    initCode();
    initWatch();
    initTrends();
    loadWatch();
    buildWatch();
    const saved = load(storeKey('view'));
    const first = S.inst.has(saved) ? saved : (S.prog.instances[0] && S.prog.instances[0].path);
    if (first) selectInstance(first);
    showTab('code');
    connect();
  }

  start();
})();
