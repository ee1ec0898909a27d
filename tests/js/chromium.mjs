// What the browser tests and the GPU benchmark share: headless Chromium as this project drives it (Debian's
// /usr/bin/chromium or $CHROMIUM, SwiftShader's WebGL 2, no background networking), and the inputs they play.
import { existsSync, readdirSync } from 'node:fs';
import path from 'node:path';

import { chromium } from 'playwright-core';

export function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
           '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
}

// The .glb and .gltf files one folder down in `directory` (none when it is absent).
export function inputsUnder(directory) {
  if (!existsSync(directory)) return [];
  return readdirSync(directory, { withFileTypes: true }).filter((e) => e.isDirectory()).flatMap((e) =>
    readdirSync(path.join(directory, e.name)).filter((f) => /\.(glb|gltf)$/.test(f)).map((f) => path.join(directory, e.name, f)));
}

// A new page of `browser` at `url`, once the page has set window.ready; its console errors and uncaught exceptions
// are collected in consoleErrors.
export async function openTestPage(browser, url) {
  const page = await browser.newPage();
  page.setDefaultTimeout(300000);
  const consoleErrors = [];
  page.on('console', (message) => { if (message.type() === 'error') consoleErrors.push(message.text()); });
  page.on('pageerror', (error) => consoleErrors.push(error.message));
  await page.goto(url);
  await page.waitForFunction(() => window.ready === true, null, { timeout: 120000 });
  return { page, consoleErrors };
}
