// <oslf-viewer src="stores/0/">: draws an OSLF store in the browser with WebGPU and the
// runtime's own shaders (served as shaders/gbuffer.wgsl and shaders/shade.wgsl, the files the
// native renderer compiles), streaming cube maps through an LRU cache fed by the frame's
// feedback, as `oslf view` does. Everything the shaders read (the uniform of each mode, the
// override constants, the pool layout, the buffers, the cube payloads) is computed by the
// runtime in Rust (oslf_runtime::web) and described by the store's manifest.json; this file
// holds what a page must do itself: the WebGPU objects, the camera, and the cache's slots.
// Attributes and events: docs/web.md.

const FORMAT_VERSION = 1;
const MAX_FETCHES = 6;
// The order of Mode::ALL, for the mode menu.
const BACKGROUNDS = { none: 0, env: 1 };

// ---- vectors (the camera's maths of renderer/camera.rs and uniform.rs) ----
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const length = (a) => Math.sqrt(dot(a, a));
function tryNormalize(a) {
  const l = length(a);
  return l > 0 && Number.isFinite(1 / l) ? scale(a, 1 / l) : null;
}
// glam's Vec3::any_orthonormal_vector.
function anyOrthonormal(v) {
  const sign = v[2] >= 0 ? 1 : -1;
  const a = -1 / (sign + v[2]);
  const b = v[0] * v[1] * a;
  return [b, sign + v[1] * v[1] * a, -v[1]];
}
// Camera::basis: right, up, forward.
function basis(cam) {
  const f = tryNormalize(sub(cam.target, cam.position)) ?? [1, 0, 0];
  const r = tryNormalize(cross(f, cam.up)) ?? anyOrthonormal(f);
  return [r, cross(r, f), f];
}
// view_projection (renderer/camera.rs): column-major, depth 0..1.
function viewProjection(cam, width, height) {
  const [r, u, f] = basis(cam);
  const p = cam.position;
  const view = [r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0,
    -dot(r, p), -dot(u, p), dot(f, p), 1];
  const dist = Math.max(length(sub(cam.target, p)), 1e-6);
  const near = dist * 1e-3, far = dist * 1e3;
  const aspect = Math.max(width, 1) / Math.max(height, 1);
  const h = 1 / Math.tan(0.5 * cam.vfov_deg * Math.PI / 180);
  const depth = far / (near - far);
  const proj = [h / aspect, 0, 0, 0, 0, h, 0, 0, 0, 0, depth, -1, 0, 0, depth * near, 0];
  const out = new Float32Array(16);
  for (let c = 0; c < 4; c++) {
    for (let row = 0; row < 4; row++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += proj[k * 4 + row] * view[c * 4 + k];
      out[c * 4 + row] = s;
    }
  }
  return out;
}
// ray_frame (uniform.rs): right with tan(vfov/2) in w, up, forward.
function rayFrame(cam) {
  const [r, u, f] = basis(cam);
  const vfov = Number.isFinite(cam.vfov_deg) ? Math.min(Math.max(cam.vfov_deg, 1e-3), 179) : 60;
  return [[...r, Math.tan(0.5 * vfov * Math.PI / 180)], [...u, 0], [...f, 0]];
}

// Whether the adapter decodes the block of `variant.probe` to its texels (within 1 %): some
// software adapters read block-compressed textures as 0. On an adapter of its own (an adapter
// gives one device).
async function decodesRight(variant) {
  const probe = variant.probe;
  if (!probe) return true;
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter?.features.has(variant.feature)) return false;
  const device = await adapter.requestDevice({ requiredFeatures: [variant.feature] });
  try {
    const tex = device.createTexture({ size: [4, 4, 1], format: variant.texture_format, usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST });
    device.queue.writeTexture({ texture: tex }, new Uint8Array(probe.block), { bytesPerRow: 16, rowsPerImage: 1 }, [4, 4, 1]);
    const module = device.createShaderModule({
      code: `@group(0) @binding(0) var t: texture_2d_array<f32>;
        @group(0) @binding(1) var<storage, read_write> o: array<vec4<f32>, 16>;
        @compute @workgroup_size(4, 4) fn main(@builtin(local_invocation_id) i: vec3<u32>) {
          o[i.y * 4u + i.x] = textureLoad(t, vec2<i32>(i.xy), 0, 0);
        }`,
    });
    const out = device.createBuffer({ size: 256, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const read = device.createBuffer({ size: 256, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const pipeline = device.createComputePipeline({ layout: 'auto', compute: { module, entryPoint: 'main' } });
    const group = device.createBindGroup({
      layout: pipeline.getBindGroupLayout(0),
      entries: [{ binding: 0, resource: tex.createView({ dimension: '2d-array' }) }, { binding: 1, resource: { buffer: out } }],
    });
    const enc = device.createCommandEncoder();
    const pass = enc.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(1);
    pass.end();
    enc.copyBufferToBuffer(out, 0, read, 0, 256);
    device.queue.submit([enc.finish()]);
    await read.mapAsync(GPUMapMode.READ);
    const got = new Float32Array(read.getMappedRange().slice(0));
    return probe.texels.every((t, i) => t.every((x, c) => Math.abs(got[i * 4 + c] - x) <= 0.01 * Math.abs(x) + 1e-4));
  } finally {
    device.destroy();
  }
}

class ViewerError extends Error {
  constructor(kind, message) {
    super(message);
    this.kind = kind;
  }
}

// A fetch that gives up on a stalled attempt (no response in HEADERS_MS, no whole body in
// BODY_MS) and tries again, at most ATTEMPTS times in all; counted in `retries`.
const ATTEMPTS = 3, HEADERS_MS = 20000, BODY_MS = 120000;
const retries = { count: 0 };

async function attempt(url, what, read) {
  const controller = new AbortController();
  let timer = setTimeout(() => controller.abort(), HEADERS_MS);
  try {
    const response = await fetch(url, { signal: controller.signal });
    clearTimeout(timer);
    timer = setTimeout(() => controller.abort(), BODY_MS);
    if (!response.ok) {
      const body = (await response.text()).trim();
      const kind = response.status === 404 ? 'missing' : 'damaged';
      throw new ViewerError(kind, `${what}: HTTP ${response.status} ${body || response.statusText}`);
    }
    return await read(response);
  } finally {
    clearTimeout(timer);
  }
}

// Fetches `url` and reads its body with `read` (`r => r.json()`, …); HTTP errors say the status
// and the server's text (404: kind `missing`, else `damaged`).
async function fetchOk(url, what, read = (r) => r.arrayBuffer()) {
  for (let i = 1; ; i++) {
    try {
      return await attempt(url, what, read);
    } catch (e) {
      if (e instanceof ViewerError) throw e;
      if (i >= ATTEMPTS) throw new ViewerError('network', `${what}: cannot fetch ${url} (${e.message}; ${ATTEMPTS} attempts)`);
      retries.count++;
    }
  }
}

const STYLE = `
  :host { display: inline-block; position: relative; background: #000; color: #eee;
          font: 13px system-ui, sans-serif; }
  canvas { display: block; touch-action: none; cursor: grab; }
  .msg { position: absolute; inset: 0; display: none; padding: 16px; box-sizing: border-box;
         background: rgba(40, 0, 0, 0.85); white-space: pre-wrap; overflow: auto; }
  .msg.shown { display: block; }
  .bar { display: flex; gap: 8px; align-items: center; padding: 4px 0; color: #ccc; }
  .bar select, .bar input { font: inherit; }
  .bar input { width: 4em; }
  .note { color: #fc6; padding: 2px 0; }
`;

export class OslfViewer extends HTMLElement {
  static get observedAttributes() {
    return ['src', 'mode', 'm', 'background', 'width', 'height', 'depth', 'glossy-filter', 'exposure'];
  }

  constructor() {
    super();
    this.stats = {
      frames: 0, requests: 0, hits: 0, misses: 0, loads: 0, bytes: 0, evictions: 0,
      overBudget: 0, firstFrameMisses: null, maxResident: 0, maxInFlight: 0,
      firstFrameMs: null, completeMs: null, failed: 0, retries: 0,
    };
    this.error = null;
    this.root = this.attachShadow({ mode: 'open' });
    this.root.innerHTML = `<style>${STYLE}</style><canvas></canvas><div class="msg"></div>
      <div class="bar" hidden><select class="mode"></select>
      <label>M <input class="m" type="number" min="1" max="1024"></label>
      <span class="status"></span></div><div class="note" hidden></div>`;
    this.canvas = this.root.querySelector('canvas');
    this.message = this.root.querySelector('.msg');
  }

  connectedCallback() {
    if (!this.started) {
      this.started = true;
      this.t0 = performance.now();
      this.start().catch((e) => this.fail(e));
    }
  }

  disconnectedCallback() {
    this.closing = true;
    this.device?.destroy();
  }

  // `src` is read once, when the element is connected; the others take effect on the next frame.
  attributeChangedCallback(name) {
    if (!this.ready || name === 'src') return;
    if (name === 'width' || name === 'height') this.resize();
    this.schedule();
  }

  fail(e) {
    const kind = e instanceof ViewerError ? e.kind : 'error';
    const message = e?.message ?? String(e);
    this.error = { kind, message };
    this.message.textContent = message;
    this.message.classList.add('shown');
    this.dispatchEvent(new CustomEvent('oslf-error', { detail: this.error, bubbles: true }));
  }

  // With the `debug` attribute, each start-up step is logged to the console.
  step(what) {
    this.stats.retries = retries.count;
    this.steps = [...(this.steps ?? []), `${Math.round(performance.now() - this.t0)} ms ${what}`];
    if (this.hasAttribute('debug')) console.log(`oslf-viewer: ${what}`);
  }

  async start() {
    const src = this.getAttribute('src');
    if (!src) throw new ViewerError('missing', 'oslf-viewer: no src attribute (the store\'s directory, e.g. stores/0/)');
    if (!navigator.gpu) {
      throw new ViewerError('no-webgpu', 'This browser has no WebGPU, which the OSLF viewer needs. ' +
        'Use a browser with WebGPU enabled (Chrome or Edge 113+, Safari 26+, Firefox 141+ on Windows).');
    }
    this.base = new URL(src.endsWith('/') ? src : `${src}/`, document.baseURI);
    this.step('manifest');
    const manifest = await fetchOk(new URL('manifest.json', this.base), 'the store\'s manifest', (r) => r.json());
    if (manifest.format !== FORMAT_VERSION) {
      throw new ViewerError('damaged', `manifest format ${manifest.format}; this page reads ${FORMAT_VERSION}`);
    }
    this.manifest = manifest;
    this.step('adapter');
    const adapter = await navigator.gpu.requestAdapter();
    this.adapter = adapter;
    this.software = adapter.info?.isFallbackAdapter || /swiftshader/i.test(`${adapter.info?.vendor} ${adapter.info?.architecture}`);
    if (!adapter) throw new ViewerError('no-webgpu', 'WebGPU is present but gives no adapter (GPU blocklisted or disabled).');
    const noBc = this.hasAttribute('no-bc');
    let variant = null;
    for (const v of manifest.variants) {
      if (!v.feature) {
        variant = v;
        break;
      }
      if (noBc || !adapter.features.has(v.feature)) continue;
      if (await decodesRight(v)) {
        variant = v;
        break;
      }
      this.formatNote = `This adapter reads ${v.texture_format} textures wrongly: the cube maps come as ${manifest.variants.at(-1).encoding} instead.`;
    }
    if (!variant) throw new ViewerError('error', 'no encoding of this store can be sampled by this adapter');
    this.variant = variant;
    const textured = manifest.textures.length > 0;
    const limits = {};
    if (textured) {
      const need = 48;
      if (adapter.limits.maxColorAttachmentBytesPerSample < need) {
        throw new ViewerError('error', `the store's textured objects need a G-buffer of ${need} bytes per sample; this adapter allows ${adapter.limits.maxColorAttachmentBytesPerSample}`);
      }
      limits.maxColorAttachmentBytesPerSample = need;
    }
    if (manifest.map_count > 256) limits.maxTextureArrayLayers = Math.min(manifest.map_count, adapter.limits.maxTextureArrayLayers);
    this.step('device');
    const device = await adapter.requestDevice({
      requiredFeatures: variant.feature ? [variant.feature] : [],
      requiredLimits: limits,
    });
    this.device = device;
    device.lost.then((info) => {
      if (!this.closing) this.fail(new ViewerError('device-lost', `The GPU device was lost (${info.reason}): ${info.message}`));
    });
    device.addEventListener('uncapturederror', (ev) => this.fail(new ViewerError('error', `WebGPU: ${ev.error.message}`)));

    const shader = async (name) => {
      const text = await fetchOk(new URL(`shaders/${name}`, import.meta.url), `shader ${name}`, (r) => r.text());
      const module = device.createShaderModule({ label: name, code: text });
      // Not awaited: the validation error scope below catches a module that fails, and this
      // says where.
      module.getCompilationInfo().then((info) => {
        const errors = info.messages.filter((m) => m.type === 'error');
        if (errors.length) this.fail(new ViewerError('error', `${name}: ${errors.map((m) => `${m.lineNum}:${m.linePos} ${m.message}`).join('\n')}`));
      });
      return module;
    };
    const resource = async (name) => new Uint8Array(await fetchOk(new URL(name, this.base), name));
    const textureNames = [];
    manifest.textures.forEach((t, o) => t.images.forEach((i) => i && textureNames.push(`texture-${o}-${i.kind}.bin`)));
    this.step('resources');
    const [gbufferModule, shadeModule, blitModule, vertices, indices, samples, patches, maps, ...images] =
      await Promise.all([shader('gbuffer.wgsl'), shader('shade.wgsl'), shader('blit.wgsl'),
        ...['vertices.bin', 'indices.bin', 'samples.bin', 'patches.bin', 'maps.bin', ...textureNames].map(resource)]);
    const imageBytes = new Map(textureNames.map((n, i) => [n, images[i]]));

    this.step('create');
    device.pushErrorScope('validation');
    this.createResources({ vertices, indices, samples, patches, maps, imageBytes });
    this.createPipelines(gbufferModule, shadeModule, blitModule);
    this.camera = { ...manifest.camera };
    this.setupCache();
    this.setupControls();
    this.resize();
    this.step('error scope');
    const error = await device.popErrorScope();
    if (error) throw new ViewerError('error', `WebGPU: ${error.message}`);
    this.step('environment cube');
    // The environment cube is pinned, loaded before the first frame as the renderer does.
    if (manifest.env_cube !== null && manifest.env_cube !== undefined) {
      const slot = this.takeSlot(0);
      this.pinned = manifest.env_cube;
      this.inFlight.set(manifest.env_cube, slot);
      await this.loadCube(manifest.env_cube, slot);
    }
    this.step('ready');
    this.ready = true;
    const notes = [];
    if (this.software && !this.hasAttribute('glossy-filter')) {
      notes.push('Software WebGPU adapter: glossy and pbr lookups are point-sampled (glossy-filter="point"), not filtered as on a GPU.');
    }
    if (this.formatNote) notes.push(this.formatNote);
    if (notes.length) {
      const note = this.root.querySelector('.note');
      note.textContent = notes.join(' ');
      note.hidden = false;
    }
    this.notes = notes;
    this.schedule();
  }

  buffer(data, usage, label) {
    const size = Math.max(4, Math.ceil(data.byteLength / 4) * 4);
    const b = this.device.createBuffer({ label, size, usage: usage | GPUBufferUsage.COPY_DST });
    this.device.queue.writeBuffer(b, 0, data.buffer, data.byteOffset, data.byteLength - (data.byteLength % 4));
    return b;
  }

  texture(desc) {
    return this.device.createTexture(desc);
  }

  createResources({ vertices, indices, samples, patches, maps, imageBytes }) {
    const m = this.manifest, v = this.variant, device = this.device;
    const storage = GPUBufferUsage.STORAGE;
    this.vertexBuffer = this.buffer(vertices, storage, 'vertices');
    this.indexBuffer = this.buffer(indices, GPUBufferUsage.INDEX, 'indices');
    this.sampleBuffer = this.buffer(samples, storage, 'samples');
    this.patchBuffer = this.buffer(patches, storage, 'patches');
    this.uniformBuffer = device.createBuffer({ label: 'params', size: m.uniform_fields.bytes, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    const tableBytes = Math.max(1, m.cube_count) * 4;
    this.slotBuffer = device.createBuffer({ label: 'slots', size: tableBytes, usage: storage | GPUBufferUsage.COPY_DST });
    this.feedbackBuffer = device.createBuffer({ label: 'feedback', size: tableBytes, usage: storage | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST });
    this.readback = device.createBuffer({ label: 'feedback readback', size: tableBytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    // Sample maps: one layer per map.
    const maps2d = this.texture({
      label: 'sample maps', size: [m.map_res, m.map_res, Math.max(1, m.map_count)],
      format: m.map_format, usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
    });
    const layerBytes = m.map_res * m.map_res * m.map_texel_bytes;
    for (let layer = 0; layer < m.map_count; layer++) {
      device.queue.writeTexture({ texture: maps2d, origin: [0, 0, layer] }, maps,
        { offset: layer * layerBytes, bytesPerRow: m.map_res * m.map_texel_bytes, rowsPerImage: m.map_res },
        [m.map_res, m.map_res, 1]);
    }
    this.mapView = maps2d.createView({ dimension: '2d-array' });
    // The cube pool: four arrays and their distance twins, placeholders where unused.
    const block = v.texture_format.startsWith('bc') ? 4 : 1;
    this.pool = [];
    this.depthPool = [];
    v.pool_sizes.forEach((size) => {
      const real = size !== null;
      const tex = this.texture({
        label: 'cube pool', size: real ? size : [block, block, 1], format: v.texture_format,
        mipLevelCount: real ? v.levels.length : 1, usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
      });
      const dtex = this.texture({
        label: 'cube distance pool', size: real && v.depth_offset !== null ? size : [1, 1, 1], format: 'r16float',
        usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
      });
      this.pool.push(tex);
      this.depthPool.push(dtex);
    });
    // The prefiltered environment of the split-sum baseline: black, as before a frame asks for it.
    this.prefiltered = this.texture({ label: 'prefiltered', size: [1, 1, 12], format: 'rgba32float', usage: GPUTextureUsage.TEXTURE_BINDING });
    // Textured objects: gbuffer.wgsl's group 1 per object.
    this.textureGroups = null;
    if (m.textures.length) {
      const fs = GPUShaderStage.FRAGMENT;
      this.textureLayout = device.createBindGroupLayout({
        label: 'object textures',
        entries: [{ binding: 0, visibility: fs, buffer: { type: 'uniform' } },
          ...m.textures[0].images.map((_, i) => ({ binding: i + 1, visibility: fs, texture: { sampleType: 'unfilterable-float' } }))],
      });
      const blank = this.texture({ size: [1, 1], format: 'rgba8unorm', usage: GPUTextureUsage.TEXTURE_BINDING });
      this.textureGroups = m.textures.map((t, o) => {
        const params = this.buffer(new Uint8Array(new Uint32Array(t.params).buffer), GPUBufferUsage.UNIFORM, 'texture params');
        const views = t.images.map((image) => {
          if (!image) return blank.createView();
          const tex = this.texture({ label: image.kind, size: [image.width, image.height], format: 'rgba8unorm', usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST });
          device.queue.writeTexture({ texture: tex }, imageBytes.get(`texture-${o}-${image.kind}.bin`), { bytesPerRow: image.width * 4, rowsPerImage: image.height }, [image.width, image.height]);
          return tex.createView();
        });
        return device.createBindGroup({
          layout: this.textureLayout,
          entries: [{ binding: 0, resource: { buffer: params } }, ...views.map((view, i) => ({ binding: i + 1, resource: view }))],
        });
      });
    }
  }

  createPipelines(gbufferModule, shadeModule, blitModule) {
    const device = this.device, textured = this.textureGroups !== null;
    const vs = GPUShaderStage.VERTEX, fs = GPUShaderStage.FRAGMENT, cs = GPUShaderStage.COMPUTE;
    // gbuffer.wgsl group 0 (pipelines.rs GBufferPipeline::bind_group_layout).
    const gLayout = device.createBindGroupLayout({
      label: 'gbuffer',
      entries: [{ binding: 0, visibility: vs | fs, buffer: { type: 'uniform' } },
        { binding: 1, visibility: vs, buffer: { type: 'read-only-storage' } }],
    });
    this.gbufferGroup = device.createBindGroup({
      layout: gLayout,
      entries: [{ binding: 0, resource: { buffer: this.uniformBuffer } }, { binding: 1, resource: { buffer: this.vertexBuffer } }],
    });
    const targets = [{ format: 'rgba32float' }, { format: 'rgba32float' }];
    if (textured) targets.push({ format: 'rgba32uint' });
    this.gbufferPipeline = device.createRenderPipeline({
      label: 'gbuffer',
      layout: device.createPipelineLayout({ bindGroupLayouts: textured ? [gLayout, this.textureLayout] : [gLayout] }),
      vertex: { module: gbufferModule, entryPoint: 'vs_main' },
      primitive: { topology: 'triangle-list', cullMode: 'none' },
      depthStencil: { format: 'depth32float', depthWriteEnabled: true, depthCompare: 'less' },
      fragment: { module: gbufferModule, entryPoint: textured ? 'fs_textured' : 'fs_main', targets },
    });
    // shade.wgsl (pipelines.rs ShadePipelines::bind_group_layout), in binding order.
    const tex = (binding, sampleType, viewDimension = '2d') => ({ binding, visibility: cs, texture: { sampleType, viewDimension } });
    const entries = [
      { binding: 0, visibility: cs, buffer: { type: 'uniform' } },
      tex(1, 'unfilterable-float'), tex(2, 'unfilterable-float'), tex(3, 'uint', '2d-array'),
      { binding: 4, visibility: cs, buffer: { type: 'read-only-storage' } },
      { binding: 5, visibility: cs, buffer: { type: 'read-only-storage' } },
      { binding: 6, visibility: cs, buffer: { type: 'read-only-storage' } },
      { binding: 7, visibility: cs, buffer: { type: 'storage' } },
    ];
    for (let b = 8; b < 16; b++) entries.push(tex(b, 'unfilterable-float', '2d-array'));
    entries.push({ binding: 16, visibility: cs, storageTexture: { access: 'write-only', format: 'rgba32float' } });
    entries.push(tex(17, 'depth'), tex(18, 'unfilterable-float', '2d-array'), tex(19, 'uint'));
    this.shadeLayout = device.createBindGroupLayout({ label: 'shade', entries });
    this.shadePipelineLayout = device.createPipelineLayout({ bindGroupLayouts: [this.shadeLayout] });
    this.shadeModule = shadeModule;
    this.shadePipelines = new Map();
    // The tone mapping of oslf view and the PNGs (view_blit.wgsl).
    this.blitLayout = device.createBindGroupLayout({
      label: 'blit',
      entries: [{ binding: 0, visibility: fs, buffer: { type: 'uniform' } },
        { binding: 1, visibility: fs, texture: { sampleType: 'unfilterable-float' } }],
    });
    this.canvasFormat = navigator.gpu.getPreferredCanvasFormat();
    this.blitPipeline = device.createRenderPipeline({
      label: 'blit',
      layout: device.createPipelineLayout({ bindGroupLayouts: [this.blitLayout] }),
      vertex: { module: blitModule, entryPoint: 'vs' },
      fragment: { module: blitModule, entryPoint: 'fs', targets: [{ format: this.canvasFormat }] },
    });
    this.blitUniform = device.createBuffer({ size: 16, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.context = this.canvas.getContext('webgpu');
    if (!this.context) throw new ViewerError('no-webgpu', 'the canvas gives no WebGPU context');
    this.context.configure({ device, format: this.canvasFormat, alphaMode: 'opaque' });
  }

  // view_blit.wgsl's uniform: the exposure, and whether to encode sRGB (not for an -srgb canvas).
  blitParams() {
    const exposure = Number(this.getAttribute('exposure') ?? 1);
    if (!(exposure >= 1e-6 && exposure <= 1e6)) throw new ViewerError('error', `exposure ${this.getAttribute('exposure')}: 1e-6 to 1e6`);
    const blit = new ArrayBuffer(16);
    new Float32Array(blit, 0, 1)[0] = exposure;
    new Uint32Array(blit, 4, 1)[0] = this.canvasFormat.endsWith('-srgb') ? 0 : 1;
    return blit;
  }

  // The mode the attributes ask for, else the store's default (as oslf render).
  currentMode() {
    const want = this.getAttribute('mode') ?? this.modeSelect?.value ?? this.manifest.default_mode;
    const mode = this.variant.modes.find((x) => x.name === want);
    if (!mode) throw new ViewerError('error', `mode ${want}: one of ${this.variant.modes.map((x) => x.name).join(', ')}`);
    return mode;
  }

  currentBackground() {
    const b = this.getAttribute('background') ?? this.manifest.default_background;
    if (!(b in BACKGROUNDS)) throw new ViewerError('error', `background ${b}: none or env`);
    if (b === 'env' && this.manifest.env_cube === null) throw new ViewerError('error', 'background env: this store has no environment cube');
    return BACKGROUNDS[b];
  }

  // `depth="off"` and `glossy-filter="point"`: as oslf render's --no-depth and
  // --glossy-filter point (the uniform's depth_steps 0 and mip_levels 1, DEPTH and FILTER off).
  switches() {
    // On a software adapter (SwiftShader), shade.wgsl's filtered-importance-sampling
    // specialization does not finish compiling in minutes: point lookups there, said on the page.
    const depth = this.getAttribute('depth') ?? 'on';
    const filter = this.getAttribute('glossy-filter') ?? (this.software ? 'point' : 'mip');
    if (!['on', 'off'].includes(depth)) throw new ViewerError('error', `depth ${depth}: on or off`);
    if (!['mip', 'point'].includes(filter)) throw new ViewerError('error', `glossy-filter ${filter}: mip or point`);
    return { depth: depth === 'on', filter: filter === 'mip' };
  }

  shadePipeline(mode, background) {
    const sw = this.switches();
    const key = `${mode.name}/${background}/${sw.depth}/${sw.filter}`;
    let p = this.shadePipelines.get(key);
    if (!p) {
      const constants = Object.fromEntries(mode.constants);
      constants.BACKGROUND = background;
      if (!sw.depth) constants.DEPTH = 0;
      if (!sw.filter) constants.FILTER = 0;
      p = this.device.createComputePipeline({
        label: `shade ${key}`, layout: this.shadePipelineLayout,
        compute: { module: this.shadeModule, entryPoint: 'shade', constants },
      });
      this.shadePipelines.set(key, p);
    }
    return p;
  }

  size() {
    const w = Number(this.getAttribute('width') ?? 0) || Math.round(this.clientWidth * devicePixelRatio) || 655;
    const h = Number(this.getAttribute('height') ?? 0) || Math.round(this.clientHeight * devicePixelRatio) || 460;
    return [Math.max(1, Math.min(8192, w)), Math.max(1, Math.min(8192, h))];
  }

  resize() {
    const [w, h] = this.size();
    if (this.targets && this.targets.w === w && this.targets.h === h) return;
    this.canvas.width = w;
    this.canvas.height = h;
    this.canvas.style.width = `${w / devicePixelRatio}px`;
    this.canvas.style.height = `${h / devicePixelRatio}px`;
    const device = this.device, usage = GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING;
    const gp = this.texture({ label: 'gb_position', size: [w, h], format: 'rgba32float', usage });
    const gn = this.texture({ label: 'gb_normal', size: [w, h], format: 'rgba32float', usage });
    const gm = this.texture({ label: 'gb_material', size: this.textureGroups ? [w, h] : [1, 1], format: 'rgba32uint', usage });
    const depth = this.texture({ label: 'depth', size: [w, h], format: 'depth32float', usage });
    const out = this.texture({ label: 'out_image', size: [w, h], format: 'rgba32float', usage: GPUTextureUsage.STORAGE_BINDING | GPUTextureUsage.TEXTURE_BINDING });
    const arr = (t) => t.createView({ dimension: '2d-array' });
    const entries = [
      { binding: 0, resource: { buffer: this.uniformBuffer } },
      { binding: 1, resource: gp.createView() }, { binding: 2, resource: gn.createView() },
      { binding: 3, resource: this.mapView },
      { binding: 4, resource: { buffer: this.sampleBuffer } }, { binding: 5, resource: { buffer: this.patchBuffer } },
      { binding: 6, resource: { buffer: this.slotBuffer } }, { binding: 7, resource: { buffer: this.feedbackBuffer } },
      ...this.pool.map((t, i) => ({ binding: 8 + i, resource: arr(t) })),
      ...this.depthPool.map((t, i) => ({ binding: 12 + i, resource: arr(t) })),
      { binding: 16, resource: out.createView() }, { binding: 17, resource: depth.createView() },
      { binding: 18, resource: arr(this.prefiltered) }, { binding: 19, resource: gm.createView() },
    ];
    this.targets = {
      w, h, gp, gn, gm, depth, out,
      shadeGroup: device.createBindGroup({ label: 'shade', layout: this.shadeLayout, entries }),
      blitGroup: device.createBindGroup({
        layout: this.blitLayout,
        entries: [{ binding: 0, resource: { buffer: this.blitUniform } }, { binding: 1, resource: out.createView() }],
      }),
    };
  }

  // The uniform of this frame: the mode's, with the camera, size, M and background written.
  uniform(mode, background) {
    const f = this.manifest.uniform_fields;
    const bytes = new ArrayBuffer(f.bytes);
    new Uint32Array(bytes).set(mode.uniform);
    const dv = new DataView(bytes);
    const [w, h] = [this.targets.w, this.targets.h];
    const o = this.manifest.origin;
    // Object-relative coordinates, as Renderer::uniform.
    const cam = { ...this.camera, position: sub(this.camera.position, o), target: sub(this.camera.target, o) };
    viewProjection(cam, w, h).forEach((x, i) => dv.setFloat32(f.view_proj + 4 * i, x, true));
    [...cam.position, 1].forEach((x, i) => dv.setFloat32(f.camera_pos + 4 * i, x, true));
    dv.setUint32(f.size, w, true);
    dv.setUint32(f.size + 4, h, true);
    const [r, u, fw] = rayFrame(cam);
    r.forEach((x, i) => dv.setFloat32(f.cam_right + 4 * i, x, true));
    u.forEach((x, i) => dv.setFloat32(f.cam_up + 4 * i, x, true));
    fw.forEach((x, i) => dv.setFloat32(f.cam_forward + 4 * i, x, true));
    const m = Number(this.getAttribute('m') ?? this.mInput?.value ?? 0);
    if (Number.isInteger(m) && m >= 1 && m <= 1024) dv.setUint32(f.m, m, true);
    dv.setUint32(f.background, background, true);
    const sw = this.switches();
    if (!sw.depth) dv.setUint32(f.depth_steps, 0, true);
    if (!sw.filter) dv.setUint32(f.mip_levels, 1, true);
    return bytes;
  }

  schedule() {
    if (!this.ready || this.error?.kind === 'device-lost') return;
    this.dirty = true;
    if (!this.drawing) {
      this.drawing = true;
      requestAnimationFrame(() => this.draw().catch((e) => this.fail(e)).finally(() => {
        this.drawing = false;
        if (this.dirty) this.schedule();
      }));
    }
  }

  async draw() {
    this.dirty = false;
    this.resize();
    const device = this.device, t = this.targets;
    const mode = this.currentMode(), background = this.currentBackground();
    device.queue.writeBuffer(this.uniformBuffer, 0, this.uniform(mode, background));
    device.queue.writeBuffer(this.slotBuffer, 0, this.table);
    device.queue.writeBuffer(this.blitUniform, 0, this.blitParams());
    const enc = device.createCommandEncoder();
    enc.clearBuffer(this.feedbackBuffer);
    const keep = { loadOp: 'load', storeOp: 'store' };
    const colors = [{ view: t.gp.createView(), ...keep }, { view: t.gn.createView(), ...keep }];
    if (this.textureGroups) colors.push({ view: t.gm.createView(), loadOp: 'clear', clearValue: [0, 0, 0, 0], storeOp: 'store' });
    const g = enc.beginRenderPass({
      colorAttachments: colors,
      depthStencilAttachment: { view: t.depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    });
    g.setPipeline(this.gbufferPipeline);
    g.setBindGroup(0, this.gbufferGroup);
    g.setIndexBuffer(this.indexBuffer, 'uint32');
    if (this.textureGroups) {
      for (const [first, count, object] of this.manifest.draws) {
        g.setBindGroup(1, this.textureGroups[object]);
        g.drawIndexed(count, 1, first);
      }
    } else {
      g.drawIndexed(this.manifest.index_count);
    }
    g.end();
    const c = enc.beginComputePass();
    c.setPipeline(this.shadePipeline(mode, background));
    c.setBindGroup(0, t.shadeGroup);
    const wg = this.manifest.workgroup;
    c.dispatchWorkgroups(Math.ceil(t.w / wg), Math.ceil(t.h / wg));
    c.end();
    const b = enc.beginRenderPass({
      colorAttachments: [{ view: this.context.getCurrentTexture().createView(), loadOp: 'clear', clearValue: [0, 0, 0, 1], storeOp: 'store' }],
    });
    b.setPipeline(this.blitPipeline);
    b.setBindGroup(0, t.blitGroup);
    b.draw(3);
    b.end();
    enc.copyBufferToBuffer(this.feedbackBuffer, 0, this.readback, 0, this.readback.size);
    device.queue.submit([enc.finish()]);
    const frame = ++this.frameIndex;
    await this.readback.mapAsync(GPUMapMode.READ);
    const needed = new Uint32Array(this.readback.getMappedRange().slice(0));
    this.readback.unmap();
    this.afterFrame(frame, needed);
  }

  // ---- the cache: slots in the pool, LRU, fed by the feedback ----

  setupCache() {
    const v = this.variant, m = this.manifest;
    this.table = new Uint32Array(Math.max(1, m.cube_count)).fill(m.no_slot);
    this.slotCube = new Int32Array(v.slots).fill(-1);
    this.slotUsed = new Float64Array(v.slots).fill(-1);
    this.free = [];
    for (let s = v.slots - 1; s >= 0; s--) this.free.push(s);
    this.resident = new Map();
    this.inFlight = new Map();
    this.queue = [];
    this.failed = new Set();
    this.pinned = null;
    this.frameIndex = 0;
    this.fetching = 0;
  }

  // A slot for a cube needed by frame `frame`: a free one, else the least recently used whose
  // cube that frame did not need; -1 when every slot holds a cube the frame needs (the budget
  // is smaller than the frame's working set: those sample points fall back, as natively).
  takeSlot(frame) {
    if (this.free.length) return this.free.pop();
    let best = -1;
    for (let s = 0; s < this.slotCube.length; s++) {
      const cube = this.slotCube[s];
      if (cube < 0 || cube === this.pinned || this.inFlight.has(cube) || this.slotUsed[s] >= frame) continue;
      if (best < 0 || this.slotUsed[s] < this.slotUsed[best]) best = s;
    }
    if (best >= 0) {
      const cube = this.slotCube[best];
      this.resident.delete(cube);
      this.table[cube] = this.manifest.no_slot;
      this.slotCube[best] = -1;
      this.stats.evictions++;
    }
    return best;
  }

  afterFrame(frame, needed) {
    const s = this.stats;
    let requests = 0, hits = 0, misses = 0;
    const want = [];
    for (let cube = 0; cube < this.manifest.cube_count; cube++) {
      if ((needed[cube] & 63) === 0) continue;
      requests++;
      const slot = this.resident.get(cube);
      if (slot !== undefined) {
        hits++;
        this.slotUsed[slot] = frame;
      } else {
        misses++;
        if (!this.inFlight.has(cube) && !this.failed.has(cube)) want.push(cube);
      }
    }
    s.frames++;
    s.requests += requests;
    s.hits += hits;
    s.misses += misses;
    if (s.firstFrameMisses === null) {
      s.firstFrameMisses = misses;
      s.firstFrameMs = performance.now() - this.t0;
      this.dispatchEvent(new CustomEvent('oslf-first-frame', { detail: { ...s }, bubbles: true }));
    }
    let over = 0;
    for (const cube of want) {
      const slot = this.takeSlot(frame);
      if (slot < 0) {
        over++;
        continue;
      }
      this.slotCube[slot] = cube;
      this.slotUsed[slot] = frame;
      this.inFlight.set(cube, slot);
      this.queue.push(cube);
    }
    s.overBudget = over;
    s.maxInFlight = Math.max(s.maxInFlight, this.inFlight.size);
    this.lastFrame = { frame, requests, hits, misses, fallbacks: misses };
    this.pump();
    this.updateStatus();
    this.dispatchEvent(new CustomEvent('oslf-frame', { detail: { ...this.lastFrame }, bubbles: true }));
    if (this.inFlight.size === 0 && !this.dirty) {
      if (s.completeMs === null) s.completeMs = performance.now() - this.t0;
      this.dispatchEvent(new CustomEvent('oslf-complete', { detail: { ...s, fallbacks: misses }, bubbles: true }));
    }
  }

  pump() {
    while (this.fetching < MAX_FETCHES && this.queue.length) {
      const cube = this.queue.shift();
      this.fetching++;
      this.loadCube(cube, this.inFlight.get(cube))
        .catch((e) => {
          this.failed.add(cube);
          this.stats.failed++;
          const slot = this.inFlight.get(cube);
          this.inFlight.delete(cube);
          if (slot !== undefined && slot >= 0) {
            this.slotCube[slot] = -1;
            this.free.push(slot);
          }
          this.fail(e);
        })
        .finally(() => {
          this.fetching--;
          this.pump();
          this.schedule();
        });
    }
  }

  // Fetches cube `cube` and uploads its six faces (every mip level, the distance plane) into
  // `slot`, as CubePool::upload places them.
  async loadCube(cube, slot) {
    const v = this.variant;
    const url = new URL(`cubes/${v.encoding}/${cube}.bin`, this.base);
    const bytes = new Uint8Array(await fetchOk(url, `cube ${cube}`));
    if (bytes.byteLength !== 6 * v.face_bytes) {
      throw new ViewerError('damaged', `cube ${cube}: ${bytes.byteLength} bytes, not ${6 * v.face_bytes}`);
    }
    const tex = Math.floor(slot / v.slots_per_texture);
    for (let face = 0; face < 6; face++) {
      const g = (slot % v.slots_per_texture) * 6 + face;
      const layer = g >> v.face_shift;
      const x = (g & ((1 << v.face_shift) - 1)) * v.cube_res;
      const at = face * v.face_bytes;
      v.levels.forEach((l, level) => {
        this.device.queue.writeTexture({ texture: this.pool[tex], mipLevel: level, origin: [x >> level, 0, layer] }, bytes,
          { offset: at + l.offset, bytesPerRow: l.row_bytes, rowsPerImage: l.rows }, [l.side, l.side, 1]);
      });
      if (v.depth_offset !== null) {
        this.device.queue.writeTexture({ texture: this.depthPool[tex], origin: [x, 0, layer] }, bytes,
          { offset: at + v.depth_offset, bytesPerRow: v.cube_res * 2, rowsPerImage: v.cube_res }, [v.cube_res, v.cube_res, 1]);
      }
    }
    this.inFlight.delete(cube);
    this.resident.set(cube, slot);
    this.slotCube[slot] = cube;
    this.table[cube] = (slot << 6) | 63;
    this.stats.loads++;
    this.stats.retries = retries.count;
    this.stats.bytes += bytes.byteLength;
    this.stats.maxResident = Math.max(this.stats.maxResident, this.resident.size);
  }

  // ---- controls: orbit, zoom, the mode and M ----

  setupControls() {
    const bar = this.root.querySelector('.bar');
    this.modeSelect = this.root.querySelector('.mode');
    this.mInput = this.root.querySelector('.m');
    for (const mode of this.variant.modes) {
      const o = document.createElement('option');
      o.value = o.textContent = mode.name;
      this.modeSelect.append(o);
    }
    this.modeSelect.value = this.getAttribute('mode') ?? this.manifest.default_mode;
    const mWord = this.manifest.uniform_fields.m / 4;
    this.mInput.value = this.getAttribute('m') ?? this.currentMode().uniform[mWord];
    if (this.hasAttribute('controls')) bar.hidden = false;
    this.modeSelect.addEventListener('change', () => {
      this.removeAttribute('mode');
      this.schedule();
    });
    this.mInput.addEventListener('change', () => {
      this.removeAttribute('m');
      this.schedule();
    });
    let drag = null;
    this.canvas.addEventListener('pointerdown', (e) => {
      drag = [e.clientX, e.clientY];
      this.canvas.setPointerCapture(e.pointerId);
    });
    this.canvas.addEventListener('pointerup', () => { drag = null; });
    this.canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      this.orbit((e.clientX - drag[0]) * 0.01, (e.clientY - drag[1]) * 0.01);
      drag = [e.clientX, e.clientY];
    });
    this.canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.zoom(Math.exp(e.deltaY * 0.001));
    }, { passive: false });
  }

  // Turns the camera about its target: `yaw` radians about the up vector, `pitch` about the
  // camera's right, stopping short of the poles.
  orbit(yaw, pitch) {
    const cam = this.camera;
    const up = tryNormalize(cam.up) ?? [0, 0, 1];
    const rot = (v, axis, a) => {
      const c = Math.cos(a), s = Math.sin(a);
      return add(add(scale(v, c), scale(cross(axis, v), s)), scale(axis, dot(axis, v) * (1 - c)));
    };
    let offset = rot(sub(cam.position, cam.target), up, -yaw);
    const [right] = basis({ ...cam, position: add(cam.target, offset) });
    const turned = rot(offset, right, -pitch);
    const cosUp = dot(tryNormalize(turned) ?? up, up);
    if (Math.abs(cosUp) < 0.995) offset = turned;
    cam.position = add(cam.target, offset);
    this.schedule();
  }

  zoom(factor) {
    const cam = this.camera;
    cam.position = add(cam.target, scale(sub(cam.position, cam.target), factor));
    this.schedule();
  }

  updateStatus() {
    const s = this.stats;
    this.root.querySelector('.status').textContent =
      `${this.resident.size}/${this.variant.slots} cubes resident, ${s.loads} loaded (${(s.bytes / 1e6).toFixed(1)} MB), ` +
      `${this.lastFrame.misses} missing this frame` + (s.overBudget ? `, ${s.overBudget} over the cache budget` : '');
  }
}

customElements.define('oslf-viewer', OslfViewer);
