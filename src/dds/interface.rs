//! A network interface's IPv4 address, by name (`lo`, `enp3s0`): deployment code names
//! interfaces (unitree_sdk2_python's `ChannelFactoryInitialize(0, "lo")`, holosoma's
//! `--task.interface lo`), while the bridge's DDS participant is restricted to addresses.

use std::ffi::CStr;
use std::net::Ipv4Addr;

/// Why an interface's address could not be found.
#[derive(Debug, thiserror::Error)]
pub enum InterfaceError {
    /// The kernel's interface list could not be read.
    #[error("listing the network interfaces: {0}")]
    List(std::io::Error),
    /// An address that is not one of this machine's interfaces.
    #[error("`option.address` {address}: {why}")]
    NotLocal {
        /// The address given.
        address: std::net::IpAddr,
        /// Why it cannot be used.
        why: String,
    },
    /// No interface of that name has an IPv4 address.
    #[error("no network interface `{name}` with an IPv4 address (those with one: {known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The interfaces that have one, with their addresses.
        known: String,
    },
}

/// Refuses an address the bridge cannot be reached on: the unspecified address (every
/// interface, which `--address` does not mean) and one no interface of this machine has
/// (8.8.8.8: DDS would bind nothing and wait for commands that cannot come).
pub fn check_local_address(address: std::net::IpAddr) -> Result<(), InterfaceError> {
    if address.is_unspecified() {
        return Err(InterfaceError::NotLocal {
            address,
            why: "it means every interface; give one interface's address (127.0.0.1 keeps DDS on this machine), or `option.interface` NAME".into(),
        });
    }
    match address {
        std::net::IpAddr::V4(v4) => {
            let all = ipv4_interfaces()?;
            if all.iter().any(|(_, a)| *a == v4) {
                Ok(())
            } else {
                Err(InterfaceError::NotLocal {
                    address,
                    why: format!(
                        "no interface of this machine has it (those with IPv4: {})",
                        all.iter()
                            .map(|(n, a)| format!("{n} {a}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })
            }
        }
        std::net::IpAddr::V6(v6) if v6.is_loopback() => Ok(()),
        std::net::IpAddr::V6(_) => Err(InterfaceError::NotLocal {
            address,
            why: "give an IPv4 address, or `option.interface` NAME".into(),
        }),
    }
}

/// The first IPv4 address of interface `name`.
pub fn ipv4_of(name: &str) -> Result<Ipv4Addr, InterfaceError> {
    let all = ipv4_interfaces()?;
    all.iter()
        .find(|(n, _)| n == name)
        .map(|&(_, address)| address)
        .ok_or_else(|| InterfaceError::Unknown {
            name: name.to_string(),
            known: all
                .iter()
                .map(|(n, a)| format!("{n} {a}"))
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// Every interface's IPv4 addresses, as (name, address), in the kernel's order.
pub fn ipv4_interfaces() -> Result<Vec<(String, Ipv4Addr)>, InterfaceError> {
    let mut head: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: on success getifaddrs points `head` at a list it allocated, which is read
    // below and freed once with freeifaddrs.
    if unsafe { libc::getifaddrs(&mut head) } != 0 {
        return Err(InterfaceError::List(std::io::Error::last_os_error()));
    }
    let mut out = Vec::new();
    let mut cursor = head;
    while !cursor.is_null() {
        // SAFETY: `cursor` is a node of the list, which stays allocated until the
        // freeifaddrs below; its name is a NUL-terminated string, and an address whose
        // family is AF_INET is a sockaddr_in.
        unsafe {
            let entry = &*cursor;
            let address = entry.ifa_addr;
            if !address.is_null() && i32::from((*address).sa_family) == libc::AF_INET {
                let ipv4 = &*(address as *const libc::sockaddr_in);
                let name = CStr::from_ptr(entry.ifa_name)
                    .to_string_lossy()
                    .into_owned();
                out.push((name, Ipv4Addr::from(u32::from_be(ipv4.sin_addr.s_addr))));
            }
            cursor = entry.ifa_next;
        }
    }
    // SAFETY: `head` came from getifaddrs and is freed once; nothing above outlives it.
    unsafe { libc::freeifaddrs(head) };
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_is_found_by_name_and_a_missing_interface_is_named() {
        assert_eq!(ipv4_of("lo").unwrap(), Ipv4Addr::LOCALHOST);
        let error = ipv4_of("no-such-nic0").unwrap_err().to_string();
        assert!(
            error.contains("no-such-nic0") && error.contains("lo 127.0.0.1"),
            "{error}"
        );
    }
}
