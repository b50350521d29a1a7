//! Link endpoints in the notation of MAVProxy, pymavlink's `mavutil.mavlink_connection` and
//! mavlink-router: `udpin:HOST:PORT`, `udpout:HOST:PORT`, `tcp:HOST:PORT`, `tcpin:HOST:PORT`,
//! and serial ports (`/dev/ttyX:BAUD` or `serial:/dev/ttyX:BAUD`).
//!
//! A [`Port`] is an open endpoint: one thread receives from it while another sends to it, so
//! both take `&self`. Datagram ends keep message boundaries; stream ends (TCP, serial) do
//! not, and the reader's [`crate::mavio::parse::Stream`] reassembles frames either way.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs, UdpSocket};
use std::sync::Mutex;
use std::time::Duration;

/// How often a blocked receive wakes up to look at the stop flag.
pub const POLL: Duration = Duration::from_millis(100);

/// An endpoint as written on the command line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// Listen for datagrams on this address; answer the last peer heard from.
    UdpIn(String),
    /// Send datagrams to this address (from an ephemeral port); receive the answers.
    UdpOut(String),
    /// Connect to a TCP server (reconnecting when it goes away).
    TcpOut(String),
    /// Listen for TCP connections; one client at a time, the newest replacing the older.
    TcpIn(String),
    /// A serial device and its baud rate.
    Serial { path: String, baud: u32 },
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Endpoint::UdpIn(a) => write!(f, "udpin:{a}"),
            Endpoint::UdpOut(a) => write!(f, "udpout:{a}"),
            Endpoint::TcpOut(a) => write!(f, "tcp:{a}"),
            Endpoint::TcpIn(a) => write!(f, "tcpin:{a}"),
            Endpoint::Serial { path, baud } => write!(f, "serial:{path}:{baud}"),
        }
    }
}

impl Endpoint {
    /// Parses an endpoint. `udp:` is MAVProxy's and pymavlink's synonym of `udpin:`;
    /// `udpbcast:` and the other pymavlink schemes are refused with the list of those known.
    pub fn parse(s: &str) -> Result<Endpoint, String> {
        let known = "udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT, /dev/ttyX:BAUD or serial:/dev/ttyX:BAUD";
        let host_port = |rest: &str| -> Result<String, String> {
            let Some((host, port)) = rest.rsplit_once(':') else {
                return Err(format!("`{s}`: expected HOST:PORT after the scheme (e.g. 127.0.0.1:14550)"));
            };
            if port.parse::<u16>().is_err() {
                return Err(format!("`{s}`: `{port}` is not a port number (0 to 65535)"));
            }
            let host = if host.is_empty() { "0.0.0.0" } else { host };
            Ok(format!("{host}:{port}"))
        };
        if let Some(rest) = s.strip_prefix("udpin:").or_else(|| s.strip_prefix("udp:")) {
            return host_port(rest).map(Endpoint::UdpIn);
        }
        if let Some(rest) = s.strip_prefix("udpout:") {
            return host_port(rest).map(Endpoint::UdpOut);
        }
        if let Some(rest) = s.strip_prefix("tcpin:") {
            return host_port(rest).map(Endpoint::TcpIn);
        }
        if let Some(rest) = s.strip_prefix("tcp:") {
            return host_port(rest).map(Endpoint::TcpOut);
        }
        let serial = s.strip_prefix("serial:").unwrap_or(s);
        if serial.starts_with('/') || serial.starts_with("COM") {
            let (path, baud) = match serial.rsplit_once(':') {
                Some((p, b)) => match b.parse::<u32>() {
                    Ok(b) if b > 0 => (p.to_string(), b),
                    _ => return Err(format!("`{s}`: `{b}` is not a baud rate (e.g. 57600)")),
                },
                None => (serial.to_string(), 57600),
            };
            return Ok(Endpoint::Serial { path, baud });
        }
        Err(format!("`{s}` is not an endpoint mochi knows; use one of {known}"))
    }

    /// Opens the endpoint (a TCP client connects on its first receive or send).
    pub fn open(&self) -> io::Result<Box<dyn Port>> {
        match self {
            Endpoint::UdpIn(a) => {
                let sock = UdpSocket::bind(resolve(a)?)?;
                sock.set_read_timeout(Some(POLL))?;
                Ok(Box::new(Udp { sock, peer: Mutex::new(None), fixed: false }))
            }
            Endpoint::UdpOut(a) => {
                let to = resolve(a)?;
                let local: SocketAddr =
                    if to.is_ipv4() { ([0, 0, 0, 0], 0).into() } else { ([0u16; 8], 0).into() };
                let sock = UdpSocket::bind(local)?;
                sock.set_read_timeout(Some(POLL))?;
                Ok(Box::new(Udp { sock, peer: Mutex::new(Some(to)), fixed: true }))
            }
            Endpoint::TcpOut(a) => Ok(Box::new(Tcp {
                mode: TcpMode::Connect(resolve(a)?),
                reader: Mutex::new(None),
                writer: Mutex::new(None),
            })),
            Endpoint::TcpIn(a) => {
                let l = TcpListener::bind(resolve(a)?)?;
                l.set_nonblocking(true)?;
                Ok(Box::new(Tcp { mode: TcpMode::Listen(l), reader: Mutex::new(None), writer: Mutex::new(None) }))
            }
            Endpoint::Serial { path, baud } => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                format!(
                    "serial port {path} at {baud} baud: mochi proxy does not open serial ports (no serial crate is a dependency); \
                     bridge the port to UDP with mavlink-router or MAVProxy (`mavproxy.py --master {path},{baud} --out udpout:127.0.0.1:14560`) \
                     and give mochi `--vehicle udpin:127.0.0.1:14560`"
                ),
            )),
        }
    }
}

fn resolve(a: &str) -> io::Result<SocketAddr> {
    a.to_socket_addrs()?
        .next()
        .ok_or_else(|| io::Error::new(io::ErrorKind::NotFound, format!("`{a}` resolves to no address")))
}

/// An open endpoint.
pub trait Port: Send + Sync {
    /// Waits at most about [`POLL`] for bytes: `Ok(0)` when none came (or a stream end went
    /// away and will be reopened), else how many were written to `buf`.
    fn recv(&self, buf: &mut [u8]) -> io::Result<usize>;
    /// Sends `data` (one datagram, or bytes on the stream). Bytes for an end not yet known
    /// (a `udpin:` nobody has sent to, a TCP end not connected) are dropped: `Ok(false)`.
    fn send(&self, data: &[u8]) -> io::Result<bool>;
    /// The local address (a `udpin:`/`tcpin:` end given port 0 learns its port here).
    fn local_addr(&self) -> Option<SocketAddr>;
}

struct Udp {
    sock: UdpSocket,
    peer: Mutex<Option<SocketAddr>>,
    /// `udpout:`: the peer is the address given, not the last one heard from.
    fixed: bool,
}

fn timed_out(e: &io::Error) -> bool {
    matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted)
}

impl Port for Udp {
    fn local_addr(&self) -> Option<SocketAddr> {
        self.sock.local_addr().ok()
    }

    fn recv(&self, buf: &mut [u8]) -> io::Result<usize> {
        match self.sock.recv_from(buf) {
            Ok((n, from)) => {
                if !self.fixed {
                    if let Ok(mut p) = self.peer.lock() {
                        if *p != Some(from) {
                            *p = Some(from);
                        }
                    }
                }
                Ok(n)
            }
            Err(e) if timed_out(&e) => Ok(0),
            // An ICMP "port unreachable" from an earlier send (nobody listening yet at a
            // `udpout:` address) surfaces here on Linux: not an error of this socket.
            Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn send(&self, data: &[u8]) -> io::Result<bool> {
        let to = match self.peer.lock() {
            Ok(p) => *p,
            Err(_) => None,
        };
        let Some(to) = to else { return Ok(false) };
        match self.sock.send_to(data, to) {
            Ok(_) => Ok(true),
            // Nobody listening (yet): the datagram is lost, as on any UDP link.
            Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => Ok(false),
            Err(e) => Err(e),
        }
    }
}

enum TcpMode {
    Connect(SocketAddr),
    Listen(TcpListener),
}

struct Tcp {
    mode: TcpMode,
    /// The receiving half, used by the one receiving thread.
    reader: Mutex<Option<TcpStream>>,
    /// The sending half (a clone of the same connection).
    writer: Mutex<Option<TcpStream>>,
}

impl Tcp {
    /// A new connection (connected, or accepted if one is waiting), installed in both halves.
    /// With `wait`, a failed attempt sleeps a little (nothing else is to be done until a peer
    /// comes); without, a listening end only looks for a waiting client.
    fn reopen(&self, wait: bool) -> io::Result<Option<TcpStream>> {
        let stream = match &self.mode {
            TcpMode::Connect(a) => match TcpStream::connect_timeout(a, POLL) {
                Ok(s) => s,
                Err(_) => {
                    std::thread::sleep(POLL);
                    return Ok(None);
                }
            },
            TcpMode::Listen(l) => match l.accept() {
                Ok((s, _)) => {
                    s.set_nonblocking(false)?;
                    s
                }
                Err(e) if timed_out(&e) => {
                    if wait {
                        std::thread::sleep(Duration::from_millis(10));
                    }
                    return Ok(None);
                }
                Err(e) => return Err(e),
            },
        };
        stream.set_nodelay(true)?;
        stream.set_read_timeout(Some(POLL))?;
        let w = stream.try_clone()?;
        if let Ok(mut slot) = self.writer.lock() {
            *slot = Some(w);
        }
        Ok(Some(stream))
    }
}

impl Port for Tcp {
    fn local_addr(&self) -> Option<SocketAddr> {
        match &self.mode {
            TcpMode::Listen(l) => l.local_addr().ok(),
            TcpMode::Connect(_) => self.writer.lock().ok()?.as_ref()?.local_addr().ok(),
        }
    }

    fn recv(&self, buf: &mut [u8]) -> io::Result<usize> {
        let mut reader = match self.reader.lock() {
            Ok(r) => r,
            Err(_) => return Ok(0),
        };
        if reader.is_none() {
            *reader = self.reopen(true)?;
        }
        let Some(s) = reader.as_mut() else { return Ok(0) };
        match s.read(buf) {
            Ok(0) => {
                *reader = None;
                if let Ok(mut w) = self.writer.lock() {
                    *w = None;
                }
                Ok(0)
            }
            Ok(n) => Ok(n),
            Err(e) if timed_out(&e) => {
                // A quiet moment: a listening end takes a newer client in place of this one
                // (a ground station that reconnected without closing the old connection).
                if matches!(self.mode, TcpMode::Listen(_)) {
                    if let Some(newer) = self.reopen(false)? {
                        *reader = Some(newer);
                    }
                }
                Ok(0)
            }
            Err(_) => {
                *reader = None;
                if let Ok(mut w) = self.writer.lock() {
                    *w = None;
                }
                Ok(0)
            }
        }
    }

    fn send(&self, data: &[u8]) -> io::Result<bool> {
        let Ok(mut w) = self.writer.lock() else { return Ok(false) };
        let Some(s) = w.as_mut() else { return Ok(false) };
        match s.write_all(data) {
            Ok(()) => Ok(true),
            Err(_) => {
                *w = None;
                Ok(false)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_are_read_as_mavlink_users_write_them() {
        assert_eq!(Endpoint::parse("udpin:0.0.0.0:14550"), Ok(Endpoint::UdpIn("0.0.0.0:14550".into())));
        assert_eq!(Endpoint::parse("udp::14550"), Ok(Endpoint::UdpIn("0.0.0.0:14550".into())));
        assert_eq!(Endpoint::parse("udpout:127.0.0.1:14551"), Ok(Endpoint::UdpOut("127.0.0.1:14551".into())));
        assert_eq!(Endpoint::parse("tcp:localhost:5760"), Ok(Endpoint::TcpOut("localhost:5760".into())));
        assert_eq!(Endpoint::parse("tcpin:0.0.0.0:5760"), Ok(Endpoint::TcpIn("0.0.0.0:5760".into())));
        assert_eq!(
            Endpoint::parse("/dev/ttyACM0:115200"),
            Ok(Endpoint::Serial { path: "/dev/ttyACM0".into(), baud: 115200 })
        );
        assert_eq!(
            Endpoint::parse("serial:/dev/ttyUSB0:57600"),
            Ok(Endpoint::Serial { path: "/dev/ttyUSB0".into(), baud: 57600 })
        );
        assert!(Endpoint::parse("udpin:1.2.3.4:99999").is_err());
        assert!(Endpoint::parse("udpout:nohost").is_err());
        assert!(Endpoint::parse("/dev/ttyS0:fast").is_err());
        let e = Endpoint::parse("udpbcast:1.2.3.4:5").unwrap_err();
        assert!(e.contains("udpin:HOST:PORT"), "{e}");
    }

    #[test]
    fn a_serial_port_is_refused_with_a_way_around() {
        let Err(e) = Endpoint::parse("/dev/ttyS0:57600").unwrap().open() else { panic!("opened a serial port") };
        assert_eq!(e.kind(), io::ErrorKind::Unsupported);
        assert!(e.to_string().contains("mavlink-router"), "{e}");
    }
}
