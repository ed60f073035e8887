#!/usr/bin/env python3
"""Timestamped UDP datagrams for the network tests (stdlib only).

send: udp_probe.py send ADDR PORT --count N --rate HZ [--first SEQ]
      each datagram: seq (u64), CLOCK_MONOTONIC send time in ns (u64), padding to --size bytes.
recv: udp_probe.py recv PORT --idle S --deadline S
      prints "ready", then, after S seconds without a datagram (or the deadline), one JSON line:
      [[seq, send_ns, recv_ns], ...] in arrival order. CLOCK_MONOTONIC is shared by all network
      namespaces of a machine, so recv_ns - send_ns is the one-way delay.
"""
import argparse
import json
import socket
import struct
import sys
import time

FMT = "<QQ"


def send(args):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    period_ns = int(1e9 / args.rate)
    t0 = time.monotonic_ns() + 1_000_000
    pad = b"\0" * max(0, args.size - struct.calcsize(FMT))
    for i in range(args.count):
        due = t0 + i * period_ns
        while True:
            left = due - time.monotonic_ns()
            if left <= 0:
                break
            if left > 300_000:
                time.sleep((left - 200_000) / 1e9)
        s.sendto(struct.pack(FMT, args.first + i, time.monotonic_ns()) + pad, (args.addr, args.port))
    print(f"sent {args.count}", flush=True)


def recv(args):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    s.bind(("0.0.0.0", args.port))
    print("ready", flush=True)
    rows = []
    deadline = time.monotonic() + args.deadline
    last = None
    while True:
        now = time.monotonic()
        wait = deadline - now if last is None else min(args.idle - (now - last), deadline - now)
        if wait <= 0:
            break
        s.settimeout(wait)
        try:
            data = s.recv(65536)
        except socket.timeout:
            break
        t_ns = time.monotonic_ns()
        seq, sent = struct.unpack_from(FMT, data)
        rows.append([seq, sent, t_ns])
        last = time.monotonic()
    print(json.dumps(rows), flush=True)


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="mode", required=True)
    a = sub.add_parser("send")
    a.add_argument("addr")
    a.add_argument("port", type=int)
    a.add_argument("--count", type=int, required=True)
    a.add_argument("--rate", type=float, default=1000)
    a.add_argument("--first", type=int, default=0)
    a.add_argument("--size", type=int, default=64)
    b = sub.add_parser("recv")
    b.add_argument("port", type=int)
    b.add_argument("--idle", type=float, default=1.0)
    b.add_argument("--deadline", type=float, default=30.0)
    args = ap.parse_args()
    send(args) if args.mode == "send" else recv(args)


if __name__ == "__main__":
    sys.exit(main())
