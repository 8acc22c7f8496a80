// H.264 frames decoded with WebCodecs. The server streams baseline profile with no B-frames and
// no reordering, so every chunk yields its picture at once (optimizeForLatency keeps the
// decoder from holding any back). A decoder error, or a session that starts mid-stream, waits
// for the next keyframe and asks the server for one; a decoder that fails `GIVE_UP_AFTER` times
// in a row without a picture (one that says it supports the stream and cannot decode it) is
// given up, and the page goes back to JPEG.

const GIVE_UP_AFTER = 3;

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
  // onFailed(why): the decoder failed GIVE_UP_AFTER times in a row; it is closed.
  constructor(width, height, { onPicture, onDropped, askKeyframe, onFailed }) {
    Object.assign(this, { width, height, onPicture, onDropped, askKeyframe, onFailed });
    this.errors = 0;
    this.failing = 0; // errors since the last picture
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
        this.failing = 0;
        if (header) this.onPicture(header, picture); else picture.close();
      },
      error: (e) => this.failed('H.264 decoder error', e),
    });
    this.decoder.configure({ codec: avcCodec(this.width, this.height), optimizeForLatency: true });
  }

  // Restarts the decoder and asks for a keyframe, or gives up after too many failures.
  failed(what, e) {
    this.errors += 1;
    this.failing += 1;
    if (this.failing < GIVE_UP_AFTER) {
      console.warn(`${what}; asking for a keyframe`, e);
      this.restart();
      return;
    }
    this.gaveUp = true;
    for (const header of this.waiting.values()) this.onDropped(header);
    this.waiting.clear();
    this.close();
    this.onFailed(`${what} ${this.failing} times in a row (${e?.message ?? e})`);
  }

  restart() {
    for (const header of this.waiting.values()) this.onDropped(header);
    if (this.decoder.state !== 'closed') this.decoder.close();
    this.start();
    this.askKeyframe();
  }

  push(header, bytes) {
    if (this.gaveUp) {
      this.onDropped(header);
      return;
    }
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
      this.failed('H.264 chunk refused', e);
    }
  }

  close() {
    if (this.decoder.state !== 'closed') this.decoder.close();
  }
}
