/** The JSON of conformance/README.md's contract, from what readPln returns. */
import { worldMatrices } from './index.mjs';

/** @param {number} v NaN as null, the JSON of the contract */
const num = (v) => (Number.isNaN(v) ? null : v);

/** @param {ReturnType<typeof import('./index.mjs').readPln>} file */
export function conformanceJson(file) {
  const c = file.container;
  const h = c.header;
  const planes = [];
  for (let i = 0; i < c.planes.length; i += 3) planes.push([c.planes[i], c.planes[i + 1], c.planes[i + 2]]);
  return {
    header: {
      version: h.version, lossy: h.lossy, coding: h.coding, bits: h.bits, h_range: h.h_range, units: h.units,
      bbox: h.bbox, tolerance: num(h.tolerance), error_bound: num(h.error_bound), counts: h.counts,
    },
    planes,
    objects: c.objects.map((o) => ({ name: o.name, parent: o.parent, transform: o.transform })),
    groups: c.groups.map(groupJson),
    colours: c.colours.map((col) => ({ group: col.group, rgba: quads(col.rgba) })),
    // mETA's keywords and a version 5 header's up axis alike (conformance/README.md)
    metadata: file.metadata,
    findings: [...c.findings],
    geometry: geometryJson(file),
  };
}

/** @param {Uint8Array} rgba */
function quads(rgba) {
  const out = [];
  for (let i = 0; i < rgba.length; i += 4) out.push([rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]]);
  return out;
}

/** @param {import('./groups.mjs').Group} g */
function groupJson(g) {
  /** @type {Record<string, any>} */
  const out = { index: g.index, object: g.object, kind: g.kind, refs: [...g.refs], bounding: [] };
  g.roles.forEach((r, i) => r && out.bounding.push(i));
  // a copy is listed as stored: its source, no kind-specific field (also where it is skipped, §9.15 step 3)
  if (g.kind === 11 && g.data) out.source = g.data.source;
  if (g.skipped) return out;
  if (g.kind === 1) out.cells = g.data.cells;
  else if (g.kind === 2) out.tree = g.data.tree;
  else if (g.kind === 5) {
    const s = g.data;
    out.vertex_planes = triples(s.cornerPlanes, s.V, null);
    out.facets = facets(s);
  } else if ((g.kind >= 6 && g.kind <= 10) || g.kind === 12 || g.kind === 13) {
    const s = g.data;
    const explicit = [];
    const grid = [];
    for (let k = 0; k < s.V; k++) {
      if (s.explicit[k]) {
        explicit.push(k);
        grid.push([s.grid[3 * k], s.grid[3 * k + 1], s.grid[3 * k + 2]]);
      }
    }
    out.shell = {
      explicit, vertex_planes: triples(s.cornerPlanes, s.V, s.explicit), grid, origin: s.origin, step: s.step, facets: facets(s),
    };
  }
  return out;
}

/** @param {Int32Array} cp @param {number} V @param {Uint8Array | null} skip */
function triples(cp, V, skip) {
  const out = [];
  for (let k = 0; k < V; k++) if (!skip || !skip[k]) out.push([cp[3 * k], cp[3 * k + 1], cp[3 * k + 2]]);
  return out;
}

/** @param {import('./shells.mjs').Shell} s */
function facets(s) {
  const out = [];
  for (let j = 0; j < s.T; j++) out.push([s.face[j], s.tri[3 * j], s.tri[3 * j + 1], s.tri[3 * j + 2]]);
  return out;
}

/**
 * The geometry section: per group its surface's summary in local coordinates, and the world box.
 * @param {ReturnType<typeof import('./index.mjs').readPln>} file
 */
function geometryJson(file) {
  const { container: c, meshes } = file;
  // read with decode: false, the file's geometry is unreported: null
  if (meshes.some((m, i) => m === null && !c.groups[i].skipped)) return null;
  const world = worldMatrices(c.objects);
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  const groups = meshes.map((mesh, i) => {
    if (!mesh) return null;
    const M = world[c.groups[i].object];
    const p = mesh.positions64;
    for (let v = 0; v < p.length; v += 3) {
      for (let r = 0; r < 3; r++) {
        const w = M[4 * r] * p[v] + M[4 * r + 1] * p[v + 1] + M[4 * r + 2] * p[v + 2] + M[4 * r + 3];
        lo[r] = Math.min(lo[r], w);
        hi[r] = Math.max(hi[r], w);
      }
    }
    // a copy's surface is its source's, placed by the copy's object (§9.15)
    return summary(mesh.positions64, mesh.indices, c.groups[mesh.source ?? i].kind);
  });
  return { world_bbox: lo[0] <= hi[0] ? [lo, hi] : null, groups };
}

/**
 * @param {Float64Array} p @param {Uint32Array} ix @param {number} kind
 */
function summary(p, ix, kind) {
  let area = 0;
  const av = [0, 0, 0];
  let volume = 0;
  for (let t = 0; t < ix.length; t += 3) {
    const a = 3 * ix[t];
    const b = 3 * ix[t + 1];
    const c = 3 * ix[t + 2];
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    area += Math.hypot(nx, ny, nz) / 2;
    av[0] += nx / 2;
    av[1] += ny / 2;
    av[2] += nz / 2;
    volume += (p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1]) - p[a + 1] * (p[b] * p[c + 2] - p[b + 2] * p[c])
      + p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c])) / 6;
  }
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let v = 0; v < p.length; v += 3) {
    for (let r = 0; r < 3; r++) {
      lo[r] = Math.min(lo[r], p[v + r]);
      hi[r] = Math.max(hi[r], p[v + r]);
    }
  }
  return {
    vertices: p.length / 3,
    triangles: ix.length / 3,
    area,
    area_vector: av,
    volume: kind <= 2 || kind === 5 ? volume : null, // solids and sealed groups (conformance/README.md)
    bbox: [lo, hi],
  };
}
