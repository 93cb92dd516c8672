"""serve --host 0.0.0.0 names the addresses a headset types, not 0.0.0.0."""
import socket

import pytest

from gigascroll.serve.run import network_urls


def _local(address: str) -> bool:
    """Independent check: only an address of this machine can be bound to."""
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    with socket.socket(family, socket.SOCK_DGRAM) as s:
        try:
            s.bind((address, 0))
        except OSError:
            return False
    return True


@pytest.mark.parametrize("url", ["http://0.0.0.0:8000/", "https://[::]:8443/"])
def test_every_address_is_this_machines_and_keeps_scheme_and_port(url):
    urls = network_urls(url)
    scheme, port = url.split("://")[0], url.rstrip("/").rsplit(":", 1)[1]
    for u in urls:
        assert u.startswith(scheme + "://") and u.endswith(f":{port}/")
        host = u.split("://")[1].rsplit(":", 1)[0].strip("[]")
        assert not host.startswith("127.") and host not in ("::1", "0.0.0.0", "::")
        assert _local(host), host
    assert len(urls) == len(set(urls))


def test_a_host_given_by_name_or_address_adds_nothing():
    for url in ("http://127.0.0.1:8000/", "http://[::1]:8000/", "https://example.org:1/",
                "http://10.1.2.3:80/", "not a url"):
        assert network_urls(url) == []
