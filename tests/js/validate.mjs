#!/usr/bin/env node
// Runs the Khronos glTF validator (npm package gltf-validator) on each file.
//
//   node validate.mjs [--verbose] FILE...
//
// One line per file: "<file>: N errors, M warnings", followed by the errors
// (code, JSON pointer, message) when N > 0; with --verbose, warnings too.
// Exit status: 0 if no file has errors, 1 if any has, 2 on bad usage or when
// a file cannot be read.

import { readFile } from 'node:fs/promises';
import path from 'node:path';
import * as validator from 'gltf-validator';

const USAGE = 'usage: node validate.mjs [--verbose] FILE...';

// Severity codes used in the validator report.
const SEVERITY = ['error', 'warning', 'info', 'hint'];

function die(message) {
  console.error(message);
  process.exit(2);
}

const args = process.argv.slice(2);
let verbose = false;
const files = [];
for (const arg of args) {
  if (arg === '--verbose' || arg === '-v') verbose = true;
  else if (arg === '--help' || arg === '-h') {
    console.log(USAGE);
    process.exit(0);
  } else if (arg.startsWith('-') && arg !== '-') die(`validate.mjs: unknown option ${arg}; ${USAGE}`);
  else files.push(arg);
}
if (files.length === 0) die(`validate.mjs: no file given; ${USAGE}`);

// Read every file up front so an unreadable one is a usage error (exit 2)
// rather than a validation failure.
const inputs = [];
for (const file of files) {
  try {
    inputs.push({ file, bytes: new Uint8Array(await readFile(file)) });
  } catch (err) {
    die(`validate.mjs: cannot read ${file}: ${err.code || err.message}`);
  }
}

function formatIssue(issue) {
  const where = issue.pointer !== undefined ? issue.pointer : issue.offset !== undefined ? `@${issue.offset}` : '-';
  return `  ${SEVERITY[issue.severity] || issue.severity} ${issue.code} ${where}: ${issue.message}`;
}

let failed = false;
for (const { file, bytes } of inputs) {
  const dir = path.dirname(path.resolve(file));
  let report;
  try {
    report = await validator.validateBytes(bytes, {
      uri: file,
      maxIssues: 0, // unlimited, so that the counts are exact
      writeTimestamp: false,
      // External buffers and images are resolved relative to the asset
      // (.gltf with .bin files; a .glb may reference external files too).
      externalResourceFunction: (uri) =>
        readFile(path.resolve(dir, decodeURIComponent(uri))).then(
          (data) => new Uint8Array(data),
          (err) => Promise.reject(`cannot read ${uri}: ${err.code || err.message}`),
        ),
    });
  } catch (err) {
    // The validator rejects input it cannot even identify as glTF or GLB.
    // That is an invalid asset, not a usage error.
    console.log(`${file}: 1 errors, 0 warnings`);
    console.log(`  error VALIDATOR_REJECTED -: ${String(err).split('\n')[0]}`);
    failed = true;
    continue;
  }
  const { numErrors, numWarnings, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings`);
  for (const issue of messages) {
    if (issue.severity === 0 || (verbose && issue.severity === 1)) console.log(formatIssue(issue));
  }
  if (numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
