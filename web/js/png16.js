// Reads the grey PNGs voxd serves (8- or 16-bit, one channel, no
// interlacing) into their exact pixel values: a browser's <img> would round
// a 16-bit radiograph to 8 bits, and the readout must say the real value.
// Inflate is the browser's own DecompressionStream.

const SIGNATURE = [137, 80, 78, 71, 13, 10, 26, 10];

async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

function paeth(a, b, c) {
  const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// { width, height, values: Uint16Array (row 0 first) }
export async function decodeGreyPng(buffer) {
  const bytes = new Uint8Array(buffer);
  const view = new DataView(buffer);
  if (!SIGNATURE.every((b, i) => bytes[i] === b)) throw new Error('not a PNG');
  let width = 0, height = 0, depth = 0;
  const idat = [];
  for (let at = 8; at + 8 <= bytes.length;) {
    const length = view.getUint32(at);
    const type = String.fromCharCode(...bytes.subarray(at + 4, at + 8));
    const data = bytes.subarray(at + 8, at + 8 + length);
    if (type === 'IHDR') {
      width = view.getUint32(at + 8);
      height = view.getUint32(at + 12);
      depth = data[8];
      if (data[9] !== 0 || data[12] !== 0) throw new Error('only grey, non-interlaced PNGs are read');
    } else if (type === 'IDAT') {
      idat.push(data);
    } else if (type === 'IEND') {
      break;
    }
    at += 12 + length;
  }
  if (depth !== 8 && depth !== 16) throw new Error(`grey PNG of ${depth} bits`);
  const raw = await inflate(new Blob(idat));
  const bpp = depth / 8, stride = width * bpp;
  const out = new Uint8Array(stride * height);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    const src = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    const row = out.subarray(y * stride, (y + 1) * stride);
    const prev = y > 0 ? out.subarray((y - 1) * stride, y * stride) : new Uint8Array(stride);
    for (let x = 0; x < stride; ++x) {
      const a = x >= bpp ? row[x - bpp] : 0, b = prev[x], c = x >= bpp ? prev[x - bpp] : 0;
      const predictor = [0, a, b, (a + b) >> 1, paeth(a, b, c)][filter];
      row[x] = (src[x] + predictor) & 255;
    }
  }
  const values = new Uint16Array(width * height);
  for (let i = 0; i < values.length; ++i) values[i] = depth === 16 ? (out[2 * i] << 8) | out[2 * i + 1] : out[i];
  return { width, height, values };
}
