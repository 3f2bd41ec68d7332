//! A bounds-checked reader of little-endian fields, shared by the XDF, TDMS
//! and ROS 2 CDR decoders: every field is checked against the bytes present before
//! it is read, and a short read names the byte offset and what was read.

/// Reads `bytes` from `at`; `base` is the offset of `bytes[0]` in the file.
pub(crate) struct Cursor<'a> {
    pub bytes: &'a [u8],
    pub at: usize,
    /// Absolute offset of `bytes[0]` in the file, for messages.
    pub base: usize,
}

impl<'a> Cursor<'a> {
    /// The next `n` bytes, or a "truncated" message.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        match self.at.checked_add(n).filter(|e| *e <= self.bytes.len()) {
            Some(end) => {
                let s = &self.bytes[self.at..end];
                self.at = end;
                Ok(s)
            }
            None => Err(format!(
                "byte {}: truncated: {what} needs {n} bytes, {} are left",
                self.base + self.at,
                self.left()
            )),
        }
    }

    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4 bytes"),
        ))
    }

    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8, what)?.try_into().expect("8 bytes"),
        ))
    }

    pub fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8, what)?.try_into().expect("8 bytes"),
        ))
    }

    /// Bytes not read yet.
    pub fn left(&self) -> usize {
        self.bytes.len() - self.at
    }
}
