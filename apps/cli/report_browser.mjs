// The browser check of `crux report` (docs/report.md, "Browser check"): opens index.html in
// headless Chromium over the DevTools protocol (--remote-debugging-pipe: no port, no network,
// no npm package), records console errors and any request that is not a local file, measures
// the verdict and every chart's text on a laptop screen (1280x800) and in print (A4 width),
// and writes a screenshot of the verdict.
//
// Usage: node report_browser.mjs INDEX_HTML --screenshot PNG --json OUT_JSON [--chromium PATH]
// Exit status: 0 when the page was measured (the findings are in OUT_JSON; the C++ test and
// the report judge them), 1 when Chromium could not be driven.

import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

const args = process.argv.slice(2);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 && i + 1 < args.length ? args[i + 1] : fallback;
};
const page = resolve(args[0] ?? 'index.html');
const screenshot = option('--screenshot', '');
const jsonPath = option('--json', '');
const chromium = option('--chromium', '/usr/bin/chromium');

const profile = mkdtempSync(join(tmpdir(), 'crux-report-chromium-'));
const browser = spawn(chromium, [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--disable-extensions', '--disable-dev-shm-usage', '--mute-audio', `--user-data-dir=${profile}`, '--remote-debugging-pipe', 'about:blank',
], { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'] });
const exited = new Promise((done) => browser.on('exit', done));
let stderr = '';
browser.stdio[2].on('data', (d) => { stderr += d; });

const pending = new Map();
const listeners = [];
let nextId = 0;
let buffer = Buffer.alloc(0);
browser.stdio[4].on('data', (chunk) => {
  buffer = Buffer.concat([buffer, chunk]);
  for (let end; (end = buffer.indexOf(0)) >= 0;) {
    const message = JSON.parse(buffer.subarray(0, end).toString());
    buffer = buffer.subarray(end + 1);
    if (message.id !== undefined && pending.has(message.id)) {
      pending.get(message.id)(message);
      pending.delete(message.id);
    } else {
      for (const listen of listeners) listen(message);
    }
  }
});
const send = (method, params = {}, sessionId = undefined) => new Promise((done, fail) => {
  const message = { id: ++nextId, method, params };
  if (sessionId) message.sessionId = sessionId;
  pending.set(message.id, (m) => (m.error ? fail(new Error(`${method}: ${m.error.message}`)) : done(m.result)));
  browser.stdio[3].write(JSON.stringify(message) + '\0');
});
const fail = (why) => {
  process.stderr.write(`report_browser: ${why}\n${stderr.slice(-2000)}\n`);
  try { browser.kill('SIGKILL'); } catch { /* gone */ }
  rmSync(profile, { recursive: true, force: true });
  process.exit(1);
};
browser.on('error', (e) => fail(`cannot start ${chromium}: ${e.message}`));
setTimeout(() => fail('timed out after 60 s'), 60000).unref();

// What the page shows, measured in the page: the verdict, and per chart its width and how far
// each of its texts reaches beyond it.
const measure = `(() => {
  const box = (e) => { const r = e.getBoundingClientRect(); return { x: r.x + scrollX, y: r.y + scrollY, width: r.width, height: r.height }; };
  const verdict = document.querySelector('#verdict');
  const charts = [...document.querySelectorAll('svg.chart')].map((svg) => {
    const s = svg.getBoundingClientRect();
    const texts = [...svg.querySelectorAll('text')];
    const beyond = (t) => { const r = t.getBoundingClientRect(); return Math.max(0, s.left - r.left, r.right - s.right, s.top - r.top, r.bottom - s.bottom); };
    const titles = [...svg.querySelectorAll('text.title')];
    return {
      series: svg.getAttribute('data-series'),
      width: s.width,
      title: titles.map((t) => t.textContent).join(' '),
      title_width: Math.max(0, ...titles.map((t) => t.getBoundingClientRect().width)),
      title_overflow: Math.max(0, ...titles.map(beyond)),
      texts: texts.length,
      texts_overflowing: texts.filter((t) => beyond(t) > 0.5).map((t) => t.textContent),
      better: [...svg.querySelectorAll('text.better')].map((t) => t.textContent).join(' '),
    };
  });
  return {
    verdict: verdict ? { ...box(verdict), text: verdict.innerText } : null,
    charts,
    document_width: document.documentElement.scrollWidth,
    wide_elements: [...document.body.querySelectorAll('*')]
      .filter((e) => e.getBoundingClientRect().right > innerWidth + 0.5 && !(e.parentElement && e.parentElement.getBoundingClientRect().right > innerWidth + 0.5))
      .map((e) => e.tagName.toLowerCase() + (e.id ? '#' + e.id : '') + (e.className && typeof e.className === 'string' ? '.' + e.className : '') +
        ' in ' + (e.closest('section')?.querySelector('h1,h2')?.textContent ?? 'body')),
    viewport_width: innerWidth,
    scripts: document.querySelectorAll('script').length,
  };
})()`;

try {
  const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
  const { sessionId } = await send('Target.attachToTarget', { targetId, flatten: true });
  const consoleErrors = [];
  const requests = [];
  let loaded = null;
  const load = new Promise((done) => { loaded = done; });
  listeners.push((m) => {
    if (m.sessionId !== sessionId) return;
    const p = m.params ?? {};
    if (m.method === 'Runtime.consoleAPICalled' && (p.type === 'error' || p.type === 'assert'))
      consoleErrors.push(p.args.map((a) => a.value ?? a.description).join(' '));
    if (m.method === 'Runtime.exceptionThrown') consoleErrors.push(p.exceptionDetails?.exception?.description ?? p.exceptionDetails?.text);
    if (m.method === 'Log.entryAdded' && p.entry.level === 'error') consoleErrors.push(`${p.entry.source}: ${p.entry.text}`);
    if (m.method === 'Network.requestWillBeSent') requests.push(p.request.url);
    if (m.method === 'Page.loadEventFired') loaded();
  });
  for (const domain of ['Runtime', 'Log', 'Network', 'Page']) await send(`${domain}.enable`, {}, sessionId);
  const laptop = { width: 1280, height: 800 };
  await send('Emulation.setDeviceMetricsOverride', { ...laptop, deviceScaleFactor: 1, mobile: false }, sessionId);
  await send('Page.navigate', { url: pathToFileURL(page).href }, sessionId);
  await load;
  const evaluate = async () => (await send('Runtime.evaluate', { expression: measure, returnByValue: true }, sessionId)).result.value;
  const screen = await evaluate();
  if (screenshot && screen.verdict) {
    const v = screen.verdict;
    const shot = await send('Page.captureScreenshot', {
      format: 'png', captureBeyondViewport: true,
      clip: { x: 0, y: Math.max(0, v.y - 8), width: laptop.width, height: v.height + 16, scale: 1 },
    }, sessionId);
    writeFileSync(screenshot, Buffer.from(shot.data, 'base64'));
  }
  // Print: A4 at 96 dpi less 2 cm margins is ~720 CSS pixels wide.
  await send('Emulation.setEmulatedMedia', { media: 'print' }, sessionId);
  await send('Emulation.setDeviceMetricsOverride', { width: 720, height: 1000, deviceScaleFactor: 1, mobile: false }, sessionId);
  const print = await evaluate();
  const local = (url) => url.startsWith('file:') || url.startsWith('data:') || url === 'about:blank';
  const result = {
    page,
    viewport: laptop,
    console_errors: consoleErrors,
    external_requests: requests.filter((u) => !local(u)),
    screen,
    print: { width: 720, document_width: print.document_width, wide_elements: print.wide_elements, charts: print.charts },
  };
  if (jsonPath) writeFileSync(jsonPath, JSON.stringify(result, null, 1) + '\n');
  else process.stdout.write(JSON.stringify(result, null, 1) + '\n');
  await send('Browser.close').catch(() => {});
} catch (e) {
  fail(e.message);
}
await Promise.race([exited, new Promise((done) => setTimeout(done, 5000))]);
browser.kill('SIGKILL');
rmSync(profile, { recursive: true, force: true });
process.exit(0);
