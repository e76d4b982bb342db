//! Live preview in the [tev](https://github.com/Tom94/tev) image viewer over its TCP protocol
//! (what pbrt-v4's `--display-server` speaks): the render creates an image in a running tev
//! (`tev` listens on 127.0.0.1:14158 by default) and sends its pixels after each pass.
//!
//! Packets (little-endian): a `u32` length of the whole packet, a `u8` type, then its fields.
//! Strings are UTF-8 and NUL-terminated. [`CREATE_IMAGE`] (4): `u8` grab focus, name, `i32`
//! width, height, channel count, the channel names. [`UPDATE_IMAGE_V3`] (6): `u8` grab focus,
//! name, `i32` channel count, the channel names, `i32` x, y, width, height of the tile, per
//! channel an `i64` offset and an `i64` stride into the `f32` samples that follow (interleaved
//! here: offset c, stride = channel count). Tiles are at most [`TILE`] pixels square, so no
//! packet is large.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

/// Packet type: create an image of given size and channels.
pub const CREATE_IMAGE: u8 = 4;
/// Packet type: update a tile of an image, with channel offsets and strides.
pub const UPDATE_IMAGE_V3: u8 = 6;
/// Edge of the tiles an update is cut into (pixels).
pub const TILE: u32 = 128;

/// A connection to tev showing one image.
pub struct TevDisplay {
    stream: TcpStream,
    name: String,
    width: u32,
    height: u32,
    channels: Vec<String>,
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    out.extend(s.bytes().filter(|&b| b != 0));
    out.push(0);
}

fn finish(mut packet: Vec<u8>) -> Vec<u8> {
    let len = packet.len() as u32;
    packet[..4].copy_from_slice(&len.to_le_bytes());
    packet
}

/// The packet creating image `name` (`width × height`, `channels`) in tev.
pub fn create_packet(name: &str, width: u32, height: u32, channels: &[String]) -> Vec<u8> {
    let mut p = vec![0u8; 4];
    p.push(CREATE_IMAGE);
    p.push(1); // grab focus
    put_str(&mut p, name);
    for v in [width as i32, height as i32, channels.len() as i32] {
        p.extend(v.to_le_bytes());
    }
    for c in channels {
        put_str(&mut p, c);
    }
    finish(p)
}

/// The packet updating the tile `[x, x + w) × [y, y + h)` of image `name` from `pixels`
/// (row-major, `image_width` wide, `channels.len()` interleaved values per pixel).
pub fn update_packet(name: &str, channels: &[String], tile: [u32; 4], pixels: &[f32], image_width: u32) -> Vec<u8> {
    let [x, y, w, h] = tile;
    let n = channels.len();
    let mut p = Vec::with_capacity(64 + (w * h) as usize * n * 4);
    p.extend([0u8; 4]);
    p.push(UPDATE_IMAGE_V3);
    p.push(0); // grab focus
    put_str(&mut p, name);
    p.extend((n as i32).to_le_bytes());
    for c in channels {
        put_str(&mut p, c);
    }
    for v in [x as i32, y as i32, w as i32, h as i32] {
        p.extend(v.to_le_bytes());
    }
    for c in 0..n {
        p.extend((c as i64).to_le_bytes());
    }
    for _ in 0..n {
        p.extend((n as i64).to_le_bytes());
    }
    for row in y..y + h {
        let start = (row as usize * image_width as usize + x as usize) * n;
        for v in &pixels[start..start + w as usize * n] {
            p.extend(v.to_le_bytes());
        }
    }
    finish(p)
}

impl TevDisplay {
    /// Connects to tev at `address` (`HOST:PORT`) and creates the image `name`.
    pub fn connect(address: &str, name: &str, width: u32, height: u32, channels: Vec<String>) -> Result<TevDisplay, String> {
        let addrs: Vec<_> = address
            .to_socket_addrs()
            .map_err(|e| format!("'{address}' is not a HOST:PORT address ({e})"))?
            .collect();
        let mut last = String::from("no address");
        for addr in addrs {
            match TcpStream::connect_timeout(&addr, Duration::from_secs(2)) {
                Ok(stream) => {
                    stream.set_nodelay(true).ok();
                    stream.set_write_timeout(Some(Duration::from_secs(10))).ok();
                    let mut d = TevDisplay { stream, name: name.to_string(), width, height, channels };
                    d.stream
                        .write_all(&create_packet(name, width, height, &d.channels))
                        .map_err(|e| format!("tev at {address}: {e}"))?;
                    return Ok(d);
                }
                Err(e) => last = e.to_string(),
            }
        }
        Err(format!("cannot connect to tev at {address}: {last} (start tev first; it listens on 127.0.0.1:14158)"))
    }

    /// Sends the whole image (`channels` interleaved values per pixel, row-major), tile by tile.
    pub fn update(&mut self, pixels: &[f32]) -> Result<(), String> {
        assert_eq!(pixels.len(), (self.width * self.height) as usize * self.channels.len());
        for ty in (0..self.height).step_by(TILE as usize) {
            for tx in (0..self.width).step_by(TILE as usize) {
                let tile = [tx, ty, TILE.min(self.width - tx), TILE.min(self.height - ty)];
                let packet = update_packet(&self.name, &self.channels, tile, pixels, self.width);
                self.stream.write_all(&packet).map_err(|e| format!("tev: {e}"))?;
            }
        }
        Ok(())
    }
}

/// A reader of tev packets, for tests (a fake tev): each packet's type and its fields.
pub mod fake {
    use std::io::Read;

    /// A parsed packet.
    #[derive(Clone, Debug, PartialEq)]
    pub enum Packet {
        /// Create an image.
        Create {
            /// Image name.
            name: String,
            /// Size.
            size: [i32; 2],
            /// Channel names.
            channels: Vec<String>,
        },
        /// Update a tile.
        Update {
            /// Image name.
            name: String,
            /// Channel names.
            channels: Vec<String>,
            /// `[x, y, width, height]`.
            tile: [i32; 4],
            /// Per channel, its values over the tile (row-major).
            values: Vec<Vec<f32>>,
        },
    }

    struct Cursor<'a>(&'a [u8]);

    impl Cursor<'_> {
        fn take(&mut self, n: usize) -> Result<&[u8], String> {
            if self.0.len() < n {
                return Err("truncated packet".into());
            }
            let (a, b) = self.0.split_at(n);
            self.0 = b;
            Ok(a)
        }
        fn i32(&mut self) -> Result<i32, String> {
            Ok(i32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
        }
        fn i64(&mut self) -> Result<i64, String> {
            Ok(i64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
        }
        fn string(&mut self) -> Result<String, String> {
            let end = self.0.iter().position(|&b| b == 0).ok_or("unterminated string")?;
            let s = String::from_utf8(self.0[..end].to_vec()).map_err(|_| "a string is not UTF-8")?;
            self.0 = &self.0[end + 1..];
            Ok(s)
        }
    }

    /// The thread of a fake tev: the packets its client sent, once it hung up.
    pub type Server = std::thread::JoinHandle<Result<Vec<Packet>, String>>;

    /// A fake tev listening on a free loopback port: its `HOST:PORT`, and a thread that accepts
    /// one client and returns the packets it sent once it hangs up.
    pub fn serve() -> std::io::Result<(String, Server)> {
        let listener = std::net::TcpListener::bind("127.0.0.1:0")?;
        let address = listener.local_addr()?.to_string();
        let server = std::thread::spawn(move || {
            let (mut stream, _) = listener.accept().map_err(|e| e.to_string())?;
            let mut packets = Vec::new();
            while let Some(p) = read_packet(&mut stream)? {
                packets.push(p);
            }
            Ok(packets)
        });
        Ok((address, server))
    }

    /// Reads one packet from `r`; `Ok(None)` at the end of the stream.
    pub fn read_packet(r: &mut impl Read) -> Result<Option<Packet>, String> {
        let mut len = [0u8; 4];
        match r.read_exact(&mut len) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
            Err(e) => return Err(e.to_string()),
        }
        let len = u32::from_le_bytes(len) as usize;
        if !(5..=1 << 30).contains(&len) {
            return Err(format!("packet length {len}"));
        }
        let mut body = vec![0u8; len - 4];
        r.read_exact(&mut body).map_err(|e| e.to_string())?;
        let mut c = Cursor(&body);
        let kind = c.take(1)?[0];
        let _focus = c.take(1)?[0];
        let name = c.string()?;
        let packet = match kind {
            super::CREATE_IMAGE => {
                let size = [c.i32()?, c.i32()?];
                let n = c.i32()?;
                let channels = (0..n).map(|_| c.string()).collect::<Result<_, _>>()?;
                Packet::Create { name, size, channels }
            }
            super::UPDATE_IMAGE_V3 => {
                let n = c.i32()? as usize;
                let channels: Vec<String> = (0..n).map(|_| c.string()).collect::<Result<_, _>>()?;
                let tile = [c.i32()?, c.i32()?, c.i32()?, c.i32()?];
                let offsets: Vec<i64> = (0..n).map(|_| c.i64()).collect::<Result<_, _>>()?;
                let strides: Vec<i64> = (0..n).map(|_| c.i64()).collect::<Result<_, _>>()?;
                let count = (tile[2] * tile[3]) as usize;
                let floats: Vec<f32> = c.0.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4"))).collect();
                let values = (0..n)
                    .map(|k| {
                        (0..count)
                            .map(|i| floats.get((offsets[k] + strides[k] * i as i64) as usize).copied().ok_or("short data"))
                            .collect::<Result<Vec<f32>, _>>()
                    })
                    .collect::<Result<_, _>>()?;
                Packet::Update { name, channels, tile, values }
            }
            other => return Err(format!("unexpected packet type {other}")),
        };
        Ok(Some(packet))
    }
}

#[cfg(test)]
mod tests {
    use super::fake::Packet;
    use super::*;

    /// A fake tev on loopback receives the image's creation, then tiles that cover it with the
    /// pixels sent (a 300 × 140 image: three tiles across, two down, clipped at the edges).
    #[test]
    fn a_fake_tev_receives_the_image() {
        let (address, server) = super::fake::serve().unwrap();
        let (w, h) = (300u32, 140u32);
        let channels: Vec<String> = ["R", "G", "B"].map(String::from).to_vec();
        let pixels: Vec<f32> = (0..w * h * 3).map(|i| i as f32 * 0.5).collect();
        let mut d = TevDisplay::connect(&address, "cbox", w, h, channels.clone()).unwrap();
        d.update(&pixels).unwrap();
        drop(d);
        let packets = server.join().unwrap().unwrap();
        assert_eq!(packets[0], Packet::Create { name: "cbox".into(), size: [300, 140], channels: channels.clone() });
        assert_eq!(packets.len(), 1 + 3 * 2);
        let mut seen = vec![0u32; (w * h) as usize];
        for p in &packets[1..] {
            let Packet::Update { name, channels: c, tile, values } = p else { panic!("{p:?}") };
            let [x, y, tw, th] = *tile;
            assert_eq!((name.as_str(), c), ("cbox", &channels));
            for j in 0..th {
                for i in 0..tw {
                    let px = ((y + j) * w as i32 + x + i) as usize;
                    seen[px] += 1;
                    for k in 0..3 {
                        assert_eq!(values[k][(j * tw + i) as usize], pixels[px * 3 + k]);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "the tiles cover the image once");
        let e = TevDisplay::connect("127.0.0.1:1", "x", 1, 1, channels).err().unwrap();
        assert!(e.contains("cannot connect to tev at 127.0.0.1:1"), "{e}");
        assert!(TevDisplay::connect("no-port", "x", 1, 1, vec![]).is_err());
    }
}
