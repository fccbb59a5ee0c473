#!/usr/bin/env python3
"""A host's link as two TAP devices joined by this process: latency without sch_netem.

Usage (root): netns-delay.py OUTER INNER NAMESPACE DELAY_FILE READY_FILE

Makes the TAP devices OUTER (left in this namespace, to be put on the bridge) and INNER (moved
into NAMESPACE; the caller renames it and gives it its address), then copies every Ethernet frame
between them. Frames from INNER (the host's egress, as `tc netem delay` on the host's eth0 would
hold them) leave DELAY_FILE milliseconds after they arrive (the file holds a number, read every
50 ms; absent or empty: 0); frames keep their order. Writes READY_FILE once both devices exist,
and runs until killed (the devices vanish with it). A device that is down drops what is written
to it, like a cable pulled out.
"""
import fcntl
import heapq
import os
import select
import struct
import subprocess
import sys
import time

TUNSETIFF = 0x400454CA
IFF_TAP, IFF_NO_PI = 0x0002, 0x1000


def tap(name):
    fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TAP | IFF_NO_PI))
    return fd


def main():
    outer, inner, ns, delay_file, ready = sys.argv[1:6]
    a, b = tap(outer), tap(inner)
    subprocess.run(["ip", "link", "set", inner, "netns", ns], check=True)
    open(ready, "w").close()
    delay, checked = 0.0, 0.0
    queue, seq = [], 0  # (due, seq, frame): frames from the host, held for the delay
    while True:
        now = time.monotonic()
        if now - checked > 0.05:
            checked = now
            try:
                delay = float(open(delay_file).read().strip() or 0) / 1000.0
            except (OSError, ValueError):
                delay = 0.0
        while queue and queue[0][0] <= now:
            try:
                os.write(a, heapq.heappop(queue)[2])
            except OSError:
                pass
        timeout = 0.05 if not queue else max(0.0, min(0.05, queue[0][0] - now))
        r, _, _ = select.select([a, b], [], [], timeout)
        for fd in r:
            while True:
                try:
                    frame = os.read(fd, 65536)
                except BlockingIOError:
                    break
                except OSError:
                    break
                if fd == a:
                    try:
                        os.write(b, frame)
                    except OSError:
                        pass
                else:
                    seq += 1
                    heapq.heappush(queue, (time.monotonic() + delay, seq, frame))


if __name__ == "__main__":
    main()
