#!/usr/bin/env node
// ort_eval.js MODEL.onnx IN.f32 ROWS OUT.f32 [STATE_IN=STATE_OUT ...]
//
// The reference for the ONNX importer's tests (pbppo import-onnx): runs MODEL.onnx with ONNX
// Runtime on the CPU, graph optimisations disabled and one intra-op thread, on ROWS rows of
// float32 little-endian input (row-major; the row width is the second dimension of the model's
// first input, which must be fixed), all rows in one batch, and writes the model's first output
// as float32 little-endian, row-major. Errors name the file and exit 1; usage errors exit 2.
// With STATE_IN=STATE_OUT pairs (a recurrent model's state inputs and outputs) the rows are one
// sequence: run one at a time, each state input zero at the first row and then the state output
// of the row before, as a controller carries it.
//
// Install once: cd tools/onnx && npm ci --ignore-scripts (tools/setup.sh does it).
'use strict';

const fs = require('fs');
const path = require('path');

const usage = 'usage: ort_eval.js MODEL.onnx IN.f32 ROWS OUT.f32 [STATE_IN=STATE_OUT ...]';

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
  if (argv.length < 4) {
    process.stderr.write(`${usage}\n`);
    process.exit(2);
  }
  const [modelPath, inPath, rowsArg, outPath] = argv;
  const pairs = argv.slice(4).map((a) => {
    const m = /^([^=]+)=([^=]+)$/.exec(a);
    if (!m) {
      process.stderr.write(`ort_eval: '${a}' is not STATE_IN=STATE_OUT\n${usage}\n`);
      process.exit(2);
    }
    return {input: m[1], output: m[2]};
  });
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

  const outName = session.outputNames[0];
  const x = decodeF32(input);
  let out;
  if (pairs.length === 0) {
    const feeds = {[meta.name]: new ort.Tensor('float32', x, [rows, width])};
    let results;
    try {
      results = await session.run(feeds);
    } catch (e) {
      fail(`${modelPath}: ONNX Runtime run failed: ${e.message}`);
    }
    const y = results[outName];
    if (y.type !== 'float32') fail(`${modelPath}: output '${outName}' is ${y.type}, not float32`);
    if (y.dims.length < 1 || y.dims[0] !== rows) {
      fail(`${modelPath}: output '${outName}' has shape [${y.dims.join(', ')}], expected ${rows} rows first`);
    }
    out = y.data;
  } else {
    // One row at a time, the state carried: zero tensors of each state input's shape (batch 1).
    const state = {};
    for (const p of pairs) {
      const i = session.inputNames.indexOf(p.input);
      if (i < 0) fail(`${modelPath}: no input '${p.input}' (inputs: ${session.inputNames.join(', ')})`);
      if (session.outputNames.indexOf(p.output) < 0) {
        fail(`${modelPath}: no output '${p.output}' (outputs: ${session.outputNames.join(', ')})`);
      }
      const shape = session.inputMetadata[i].shape.map((d) => (typeof d === 'number' ? d : 1));
      state[p.input] = new ort.Tensor('float32', new Float32Array(shape.reduce((a, b) => a * b, 1)), shape);
    }
    const parts = [];
    for (let r = 0; r < rows; ++r) {
      const feeds = {[meta.name]: new ort.Tensor('float32', x.slice(r * width, (r + 1) * width), [1, width])};
      for (const p of pairs) feeds[p.input] = state[p.input];
      let results;
      try {
        results = await session.run(feeds);
      } catch (e) {
        fail(`${modelPath}: ONNX Runtime run failed at row ${r}: ${e.message}`);
      }
      const y = results[outName];
      if (y.type !== 'float32') fail(`${modelPath}: output '${outName}' is ${y.type}, not float32`);
      parts.push(y.data);
      for (const p of pairs) state[p.input] = results[p.output];
    }
    out = new Float32Array(parts.reduce((n, a) => n + a.length, 0));
    let at = 0;
    for (const a of parts) {
      out.set(a, at);
      at += a.length;
    }
  }
  try {
    fs.writeFileSync(outPath, encodeF32(out));
  } catch (e) {
    fail(`${outPath}: cannot write (${e.code || e.message})`);
  }
  await session.release();
}

main(process.argv.slice(2)).catch((e) => fail(e.stack || String(e)));
