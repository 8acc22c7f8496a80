// H.264 frames decoded with WebCodecs. The server streams baseline profile with no B-frames and
// no reordering, so every chunk yields its picture at once (optimizeForLatency keeps the
// decoder from holding any back). A decoder error, or a session that starts mid-stream, waits
// for the next keyframe and asks the server for one.

// The codec string: constrained baseline at the level the frame size needs.
export function avcCodec(width, height) {
  const mbs = Math.ceil(width / 16) * Math.ceil(height / 16);
  const level = mbs <= 1620 ? 0x1f : mbs <= 8192 ? 0x28 : 0x33; // 3.1, 4.0, 5.1
  return `avc1.42E0${level.toString(16).toUpperCase()}`;
}

// Whether this browser can decode the stream (WebCodecs present and the codec supported).
export async function h264Supported(width, height) {
  if (!('VideoDecoder' in window) || !('EncodedVideoChunk' in window)) return false;
  try {
    const r = await VideoDecoder.isConfigSupported({ codec: avcCodec(width, height), optimizeForLatency: true });
    return Boolean(r.supported);
  } catch {
    return false;
  }
}

export class H264Player {
  // onPicture(header, videoFrame): a decoded frame to show (the callee closes it).
  // onDropped(header): a frame that will not be shown (its credit goes back).
  // askKeyframe(): tell the server the next frame must be a keyframe.
  constructor(width, height, { onPicture, onDropped, askKeyframe }) {
    Object.assign(this, { width, height, onPicture, onDropped, askKeyframe });
    this.errors = 0;
    this.decoded = 0;
    this.keyframes = 0; // of the chunks decoded
    this.start();
  }

  start() {
    this.waiting = new Map(); // chunk timestamp → header
    this.needKey = true;
    this.decoder = new VideoDecoder({
      output: (picture) => {
        const header = this.waiting.get(picture.timestamp);
        this.waiting.delete(picture.timestamp);
        this.decoded += 1;
        if (header) this.onPicture(header, picture); else picture.close();
      },
      error: (e) => {
        console.warn('H.264 decoder error; asking for a keyframe', e);
        this.errors += 1;
        this.restart();
      },
    });
    this.decoder.configure({ codec: avcCodec(this.width, this.height), optimizeForLatency: true });
  }

  restart() {
    for (const header of this.waiting.values()) this.onDropped(header);
    if (this.decoder.state !== 'closed') this.decoder.close();
    this.start();
    this.askKeyframe();
  }

  push(header, bytes) {
    if (this.needKey && !header.keyframe) {
      // A delta frame without its reference cannot be decoded: skip to the next keyframe.
      this.onDropped(header);
      if (!this.asked) this.askKeyframe();
      this.asked = true;
      return;
    }
    this.needKey = false;
    this.asked = false;
    if (header.keyframe) this.keyframes += 1;
    const timestamp = header.frame * 1000; // microseconds; unique per session
    this.waiting.set(timestamp, header);
    try {
      this.decoder.decode(new EncodedVideoChunk({ type: header.keyframe ? 'key' : 'delta', timestamp, data: bytes }));
    } catch (e) {
      console.warn('H.264 chunk refused; asking for a keyframe', e);
      this.errors += 1;
      this.restart();
    }
  }

  close() {
    if (this.decoder.state !== 'closed') this.decoder.close();
  }
}
