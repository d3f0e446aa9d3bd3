"""Checkpoint files of the campaign tests (STORE.checkpoints/*.ckpt, docs/store.md): the body and
its CRC-32C, for tests that rewrite a file and recompute the checksum as a hand edit would."""
import struct


def crc32c(data):
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    c = 0xFFFFFFFF
    for b in data:
        c = table[(c ^ b) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


def read_body(path):
    """The file without its checksum, after checking the checksum."""
    b = open(path, "rb").read()
    body = b[:-4]
    assert struct.unpack("<I", b[-4:])[0] == crc32c(body), "checksum layout"
    return body


def write_body(path, body):
    """Writes body and its CRC-32C."""
    body = bytes(body)
    open(path, "wb").write(body + struct.pack("<I", crc32c(body)))
