//! One I420 picture as the H.264 encoder reads it and the stream's hold (`encode::hold`)
//! compares it: filled from RGBA (`yuv::rgba_to_i420`), from the GPU's planes, or from a
//! decoded picture.

use super::yuv::rgba_to_i420;

/// One I420 picture (Y, then U, then V, tightly packed), as openh264 reads it.
#[derive(Clone)]
pub struct I420 {
    data: Vec<u8>,
    width: usize,
    height: usize,
}

impl I420 {
    pub fn new(width: usize, height: usize) -> I420 {
        I420 {
            data: vec![0; width * height * 3 / 2],
            width,
            height,
        }
    }

    /// Refills the picture from I420 planes of the same size (Y, U, V, tight).
    pub fn copy_from(&mut self, planes: &[u8]) {
        self.data.copy_from_slice(planes);
    }

    /// The Y, U and V planes, to write.
    pub fn planes_mut(&mut self) -> (&mut [u8], &mut [u8], &mut [u8]) {
        let n = self.width * self.height;
        let (y, chroma) = self.data.split_at_mut(n);
        let (u, v) = chroma.split_at_mut(n / 4);
        (y, u, v)
    }

    /// Refills the picture from a decoded one of the same size (planes with strides).
    pub fn copy_from_source(&mut self, pic: &impl openh264::formats::YUVSource) {
        let (w, h) = (self.width, self.height);
        let (sy, su, sv) = pic.strides();
        let (y, u, v) = self.planes_mut();
        for (plane, from, stride, pw, ph) in [
            (y, pic.y(), sy, w, h),
            (u, pic.u(), su, w / 2, h / 2),
            (v, pic.v(), sv, w / 2, h / 2),
        ] {
            for (row, src) in plane.chunks_exact_mut(pw).zip(from.chunks(stride)).take(ph) {
                row.copy_from_slice(&src[..pw]);
            }
        }
    }

    /// Refills the picture from `rgba` of the same (even) size.
    pub fn fill(&mut self, rgba: &[u8]) {
        let (w, h) = (self.width, self.height);
        let (y, u, v) = self.planes_mut();
        rgba_to_i420(rgba, w, h, y, u, v);
    }
}

impl openh264::formats::YUVSource for I420 {
    fn dimensions(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn strides(&self) -> (usize, usize, usize) {
        (self.width, self.width / 2, self.width / 2)
    }

    fn y(&self) -> &[u8] {
        &self.data[..self.width * self.height]
    }

    fn u(&self) -> &[u8] {
        let n = self.width * self.height;
        &self.data[n..n + n / 4]
    }

    fn v(&self) -> &[u8] {
        let n = self.width * self.height;
        &self.data[n + n / 4..]
    }
}
