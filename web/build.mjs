// Builds the two self-contained pages: viewer.html and report.html.
//
//   node build.mjs --outdir DIR
//
// Each page is one HTML file with its JavaScript and CSS inlined, so it opens from disk
// (file://) and needs no network. The C++ side replaces the data placeholders
// (docs/replay.md); this script checks that each appears exactly once in its page.
import { createHash } from 'node:crypto';
import { existsSync, mkdirSync, readFileSync, renameSync, writeFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));

function fail(message) {
  console.error(`web build: ${message}`);
  process.exit(1);
}

function parseArgs(argv) {
  const args = { outdir: join(here, 'dist') };
  for (let i = 0; i < argv.length; ++i) {
    if (argv[i] === '--outdir' && i + 1 < argv.length) args.outdir = resolve(argv[++i]);
    else fail(`unknown argument '${argv[i]}' (usage: node build.mjs --outdir DIR)`);
  }
  return args;
}

/// The stamp scripts/install-deps.sh writes after `npm ci`: the lockfile's hash.
export function lockHash() {
  return createHash('sha256').update(readFileSync(join(here, 'package-lock.json'))).digest('hex');
}

function checkNodeModules() {
  const modules = join(here, 'node_modules');
  if (!existsSync(join(modules, 'esbuild')) || !existsSync(join(modules, 'uplot')) ||
      !existsSync(join(modules, 'fflate'))) {
    fail(`${modules} is missing: run scripts/install-deps.sh (it runs npm ci in web/)`);
  }
  const stamp = join(modules, '.overtake-lock-sha256');
  if (existsSync(stamp) && readFileSync(stamp, 'utf8').trim() !== lockHash()) {
    fail(`${modules} is stale (package-lock.json changed since npm ci): run scripts/install-deps.sh`);
  }
}

// Keeps inlined code from closing its <script> or <style> element early.
function escapeForInline(text, tag) {
  return text.replace(new RegExp(`</(${tag})`, 'gi'), '<\\/$1');
}

const PLACEHOLDERS = {
  viewer: ['__OVERTAKE_CONFIG__', '__OVERTAKE_DATA__'],
  report: ['__OVERTAKE_BENCH__'],
};

async function buildPage(esbuild, name, outdir) {
  const result = await esbuild.build({
    entryPoints: [join(here, 'src', name, 'main.js')],
    bundle: true,
    minify: true,
    format: 'iife',
    target: ['chrome110', 'firefox110', 'safari16'],
    platform: 'browser',
    legalComments: 'none',
    write: false,
    outdir: join(here, '.out'),
    loader: { '.css': 'css' },
    logLevel: 'warning',
  });
  let js = '';
  let css = '';
  for (const f of result.outputFiles) {
    if (f.path.endsWith('.js')) js += f.text;
    else if (f.path.endsWith('.css')) css += f.text;
  }
  const template = readFileSync(join(here, 'src', name, 'index.html'), 'utf8');
  if (!template.includes('<!-- STYLE -->') || !template.includes('<!-- SCRIPT -->')) {
    fail(`src/${name}/index.html needs the <!-- STYLE --> and <!-- SCRIPT --> markers`);
  }
  const html = template
    .replace('<!-- STYLE -->', () => `<style>${escapeForInline(css, 'style')}</style>`)
    .replace('<!-- SCRIPT -->', () => `<script>${escapeForInline(js, 'script')}</script>`);
  for (const p of PLACEHOLDERS[name]) {
    const count = html.split(p).length - 1;
    if (count !== 1) fail(`${name}.html holds the placeholder ${p} ${count} times (must be exactly once)`);
  }
  if (/\b(src|href)\s*=\s*["']?(https?:)?\/\//i.test(html)) {
    fail(`${name}.html refers to an external resource; pages must be self-contained`);
  }
  const out = join(outdir, `${name}.html`);
  writeFileSync(`${out}.tmp`, html);
  renameSync(`${out}.tmp`, out);
  return { out, bytes: Buffer.byteLength(html) };
}

async function main() {
  const { outdir } = parseArgs(process.argv.slice(2));
  checkNodeModules();
  const esbuild = await import('esbuild');
  mkdirSync(outdir, { recursive: true });
  for (const name of ['viewer', 'report']) {
    const { out, bytes } = await buildPage(esbuild, name, outdir);
    console.log(`web build: ${out} (${(bytes / 1024).toFixed(0)} KiB)`);
  }
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  main().catch((e) => fail(e && e.message ? e.message : String(e)));
}
