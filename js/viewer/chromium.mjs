/**
 * Headless Chromium for the viewer's test and screenshot: Debian's `chromium` package driven by
 * playwright-core (which downloads no browser of its own). WebGL runs on SwiftShader, the software
 * renderer Chromium ships; the background-networking flags keep Chromium from stalling on a
 * machine without a network.
 */
import fs from 'node:fs';

export const CHROMIUM = process.env.PLN_CHROMIUM ?? '/usr/bin/chromium';

export const ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
];

/** Why the browser cannot run here, or null. */
export async function problem() {
  if (!fs.existsSync(CHROMIUM)) {
    return `${CHROMIUM} is missing (make setup installs Debian's chromium where it runs as root with apt-get)`;
  }
  try {
    await import('playwright-core');
  } catch {
    return 'playwright-core is missing (cd js && npm ci)';
  }
  return null;
}

/** @param {{width?: number, height?: number}} [size] */
export async function launch({ width = 1280, height = 800 } = {}) {
  const { chromium } = await import('playwright-core');
  const browser = await chromium.launch({ executablePath: CHROMIUM, args: ARGS, headless: true, timeout: 20000 });
  const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
  /** @type {string[]} */
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  return { browser, page, consoleErrors };
}
