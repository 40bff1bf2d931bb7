// SPDX-License-Identifier: Apache-2.0
// A second, independent C3D reader (node, no dependencies), written from c3d.org's format guide
// apart from the C++ one in common/mocap_formats, used to check what the C++ side writes and
// reads (tests/integration/test_c3d_export.sh). No npm registry package reads C3D (docs/recording.md).
//
//   node read_c3d.js FILE            prints {processor, points, rate, frames, units, labels} as JSON
//   node read_c3d.js FILE --trc TRC  also compares every point with a TRC file; prints max_error_m
'use strict';
const fs = require('fs');

function decoder(buf, processor) {
  const big = processor === 86;
  const int16 = (o) => (big ? buf.readInt16BE(o) : buf.readInt16LE(o));
  const float = (o) => {
    if (processor === 84) return buf.readFloatLE(o);
    if (processor === 86) return buf.readFloatBE(o);
    // DEC: swap the 16-bit halves, read as IEEE, the exponent is 2 too large.
    const b = Buffer.from([buf[o + 2], buf[o + 3], buf[o], buf[o + 1]]);
    const v = b.readFloatLE(0);
    return v === 0 ? 0 : v / 4;
  };
  return { int16, float };
}

function readC3d(path) {
  const buf = fs.readFileSync(path);
  if (buf.length < 512 || buf[1] !== 0x50) throw new Error(`${path}: not a C3D file`);
  const paramStart = (buf[0] - 1) * 512;
  const processor = buf[paramStart + 3];
  if (processor < 84 || processor > 86) throw new Error(`${path}: processor byte ${processor}`);
  const d = decoder(buf, processor);
  const groups = {};
  const params = [];
  let p = paramStart + 4;
  for (;;) {
    const nameLen = Math.abs(buf.readInt8(p));
    if (nameLen === 0) break;
    const id = buf.readInt8(p + 1);
    const name = buf.toString('latin1', p + 2, p + 2 + nameLen).toUpperCase();
    const next = d.int16(p + 2 + nameLen);
    const body = p + 4 + nameLen;
    if (id < 0) {
      groups[-id] = name;
    } else {
      const type = buf.readInt8(body);
      const ndim = buf[body + 1];
      const dims = [];
      for (let i = 0; i < ndim; i++) dims.push(buf[body + 2 + i]);
      const data = body + 2 + ndim;
      const count = dims.reduce((a, b) => a * b, 1);
      let value;
      if (type === -1) {
        const w = ndim === 0 ? 1 : dims[0];
        value = [];
        for (let i = 0; i < count; i += w) value.push(buf.toString('latin1', data + i, data + i + w).replace(/[\s\0]+$/, ''));
      } else {
        value = [];
        for (let i = 0; i < count; i++) {
          if (type === 1) value.push(buf[data + i]);
          else if (type === 2) value.push(d.int16(data + 2 * i));
          else value.push(d.float(data + 4 * i));
        }
      }
      params.push({ id, name, value });
    }
    if (next === 0) break;
    p = p + 2 + nameLen + next;
  }
  const get = (group, name) => {
    const hit = params.find((q) => groups[q.id] === group && q.name === name);
    return hit ? hit.value : undefined;
  };
  const points = (get('POINT', 'USED')[0] + 65536) % 65536;
  const scale = get('POINT', 'SCALE') ? get('POINT', 'SCALE')[0] : d.float(12);
  const rate = get('POINT', 'RATE') ? get('POINT', 'RATE')[0] : d.float(20);
  let labels = [];
  for (let i = 1; labels.length < points; i++) {
    const l = get('POINT', i === 1 ? 'LABELS' : `LABELS${i}`);
    if (!l) break;
    labels = labels.concat(l);
  }
  labels = labels.slice(0, points);
  const unitsParam = get('POINT', 'UNITS');
  const units = unitsParam ? unitsParam[0] : 'mm';
  const first = (d.int16(6) + 65536) % 65536;
  const last = (d.int16(8) + 65536) % 65536;
  let frames = last - first + 1;
  const end = get('TRIAL', 'ACTUAL_END_FIELD');
  const start = get('TRIAL', 'ACTUAL_START_FIELD');
  if (end && start) frames = (((end[0] & 0xffff) + (end[1] & 0xffff) * 65536) - ((start[0] & 0xffff) + (start[1] & 0xffff) * 65536)) + 1;
  const dataStartParam = get('POINT', 'DATA_START');
  const dataStart = ((dataStartParam ? (dataStartParam[0] + 65536) % 65536 : d.int16(16)) - 1) * 512;
  const analog = (d.int16(4) + 65536) % 65536;
  const isFloat = scale < 0;
  const word = isFloat ? 4 : 2;
  const frameBytes = (points * 4 + analog) * word;
  const toMetres = { mm: 1e-3, cm: 1e-2, m: 1 }[units];
  const sample = (f, m) => {
    const o = dataStart + f * frameBytes + m * 4 * word;
    if (isFloat) {
      const w4 = Math.trunc(d.float(o + 12));
      return w4 < 0 ? null : [d.float(o), d.float(o + 4), d.float(o + 8)].map((v) => v * toMetres);
    }
    const w4 = d.int16(o + 6);
    return w4 < 0 ? null : [d.int16(o), d.int16(o + 2), d.int16(o + 4)].map((v) => v * Math.abs(scale) * toMetres);
  };
  return { processor, points, rate, frames, units, labels, scale, sample, complete: dataStart + frames * frameBytes <= buf.length };
}

function readTrc(path) {
  const lines = fs.readFileSync(path, 'latin1').split(/\r?\n/);
  const keys = lines[1].trim().split(/\s+/);
  const values = lines[2].trim().split(/\s+/);
  const units = values[keys.indexOf('Units')];
  const toMetres = { mm: 1e-3, cm: 1e-2, m: 1 }[units];
  const rows = lines.slice(5).filter((l) => l.trim() !== '').map((l) => l.split('\t'));
  return rows.map((r) => r.slice(2).map((v) => (v.trim() === '' ? null : Number(v) * toMetres)));
}

const args = process.argv.slice(2);
const c3d = readC3d(args[0]);
const out = { processor: c3d.processor, points: c3d.points, rate: c3d.rate, frames: c3d.frames, units: c3d.units,
  labels: c3d.labels, complete: c3d.complete };
const trcIndex = args.indexOf('--trc');
if (trcIndex >= 0) {
  const rows = readTrc(args[trcIndex + 1]);
  let maxError = 0;
  let compared = 0;
  let mismatchedValidity = 0;
  if (rows.length !== c3d.frames) throw new Error(`frames: TRC ${rows.length}, C3D ${c3d.frames}`);
  for (let f = 0; f < c3d.frames; f++) {
    for (let m = 0; m < c3d.points; m++) {
      const p = c3d.sample(f, m);
      const ref = rows[f].slice(3 * m, 3 * m + 3);
      const refValid = ref.length === 3 && ref.every((v) => v !== null && v !== undefined);
      if ((p !== null) !== refValid) { mismatchedValidity++; continue; }
      if (p === null) continue;
      for (let a = 0; a < 3; a++) maxError = Math.max(maxError, Math.abs(p[a] - ref[a]));
      compared++;
    }
  }
  Object.assign(out, { compared, mismatched_validity: mismatchedValidity, max_error_m: maxError });
}
console.log(JSON.stringify(out));
