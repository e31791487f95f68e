#!/usr/bin/env node
// ort_eval.js MODEL.onnx IN.f32 ROWS OUT.f32
//
// The reference for the ONNX importer's tests (pbppo import-onnx): runs MODEL.onnx with ONNX
// Runtime on the CPU, graph optimisations disabled and one intra-op thread, on ROWS rows of
// float32 little-endian input (row-major; the row width is the second dimension of the model's
// first input, which must be fixed), all rows in one batch, and writes the model's first output
// as float32 little-endian, row-major. Errors name the file and exit 1; usage errors exit 2.
//
// Install once: cd tools/onnx && npm ci --ignore-scripts (tools/setup.sh does it).
'use strict';

const fs = require('fs');
const path = require('path');

const usage = 'usage: ort_eval.js MODEL.onnx IN.f32 ROWS OUT.f32';

function fail(message) {
  process.stderr.write(`ort_eval: ${message}\n`);
  process.exit(1);
}

function loadOrt() {
  try {
    return require('onnxruntime-node');
  } catch (e) {
    fail(`cannot load onnxruntime-node (${e.message}); install it: cd ${__dirname} && npm ci --ignore-scripts`);
  }
  return null;
}

function readFileOrFail(file) {
  try {
    return fs.readFileSync(file);
  } catch (e) {
    fail(`${file}: cannot read (${e.code || e.message})`);
  }
  return null;
}

// float32 little-endian bytes -> Float32Array, whatever the host's byte order.
function decodeF32(bytes) {
  const n = bytes.length / 4;
  const out = new Float32Array(n);
  for (let i = 0; i < n; ++i) out[i] = bytes.readFloatLE(4 * i);
  return out;
}

function encodeF32(values) {
  const buf = Buffer.alloc(values.length * 4);
  for (let i = 0; i < values.length; ++i) buf.writeFloatLE(values[i], 4 * i);
  return buf;
}

async function main(argv) {
  if (argv.length !== 4) {
    process.stderr.write(`${usage}\n`);
    process.exit(2);
  }
  const [modelPath, inPath, rowsArg, outPath] = argv;
  if (!/^[1-9][0-9]*$/.test(rowsArg) || Number(rowsArg) > 1e7) {
    process.stderr.write(`ort_eval: ROWS '${rowsArg}' is not a positive row count\n${usage}\n`);
    process.exit(2);
  }
  const rows = Number(rowsArg);
  if (!fs.existsSync(modelPath)) fail(`${modelPath}: no such model file`);
  const input = readFileOrFail(inPath);

  const ort = loadOrt();
  let session;
  try {
    session = await ort.InferenceSession.create(modelPath, {
      executionProviders: ['cpu'],
      graphOptimizationLevel: 'disabled',
      intraOpNumThreads: 1,
      interOpNumThreads: 1,
      executionMode: 'sequential',
    });
  } catch (e) {
    fail(`${modelPath}: ONNX Runtime cannot load the model: ${e.message}`);
  }

  const meta = session.inputMetadata[0];
  if (!meta || !meta.isTensor) fail(`${modelPath}: the first input is not a tensor`);
  if (meta.type !== 'float32') fail(`${modelPath}: input '${meta.name}' is ${meta.type}, not float32`);
  if (meta.shape.length !== 2) {
    fail(`${modelPath}: input '${meta.name}' has shape [${meta.shape.join(', ')}], not [batch, width]`);
  }
  const width = meta.shape[1];
  if (typeof width !== 'number' || !(width > 0)) {
    fail(`${modelPath}: input '${meta.name}' has no fixed width (second dimension '${width}')`);
  }
  if (input.length !== rows * width * 4) {
    fail(
      `${inPath}: ${input.length} bytes, but ${rows} rows of ${width} float32 (input '${meta.name}' of ` +
        `${path.basename(modelPath)}) are ${rows * width * 4} bytes`,
    );
  }

  const feeds = {[meta.name]: new ort.Tensor('float32', decodeF32(input), [rows, width])};
  let results;
  try {
    results = await session.run(feeds);
  } catch (e) {
    fail(`${modelPath}: ONNX Runtime run failed: ${e.message}`);
  }
  const outName = session.outputNames[0];
  const y = results[outName];
  if (y.type !== 'float32') fail(`${modelPath}: output '${outName}' is ${y.type}, not float32`);
  if (y.dims.length < 1 || y.dims[0] !== rows) {
    fail(`${modelPath}: output '${outName}' has shape [${y.dims.join(', ')}], expected ${rows} rows first`);
  }
  try {
    fs.writeFileSync(outPath, encodeF32(y.data));
  } catch (e) {
    fail(`${outPath}: cannot write (${e.code || e.message})`);
  }
  await session.release();
}

main(process.argv.slice(2)).catch((e) => fail(e.stack || String(e)));
