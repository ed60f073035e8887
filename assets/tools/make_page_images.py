#!/usr/bin/env python3
"""Draws the pictures on the start menu's book pages (assets/images/*.png).

Simple flat drawings, 240 x 320 px (a page is 10 x 14 cm), made with Pillow so that they can be
regenerated and changed like the meshes (assets/tools/make_meshes.py). The scene files name
them in their books' pages; graphics nodes draw them on the left page of an open book.

usage: assets/tools/make_page_images.py [OUT_DIR]   (default: assets/images beside this folder)
"""
import math
import os
import sys

from PIL import Image, ImageDraw

W, H = 240, 320
INK = (40, 36, 30)


def canvas(rgb):
    image = Image.new("RGB", (W, H), rgb)
    return image, ImageDraw.Draw(image)


def disk(d, cx, cy, r, fill, outline=None, width=1):
    d.ellipse((cx - r, cy - r, cx + r, cy + r), fill=fill, outline=outline, width=width)


def arrow_down(d, x, y0, length, fill, width=5):
    d.line((x, y0, x, y0 + length), fill=fill, width=width)
    d.polygon([(x - 8, y0 + length - 2), (x + 8, y0 + length - 2), (x, y0 + length + 12)], fill=fill)


def solar_system():
    image, d = canvas((14, 18, 44))
    for k, (x, y) in enumerate([(30, 40), (200, 60), (120, 290), (215, 250), (60, 200), (170, 150)]):
        disk(d, x, y, 1 + k % 2, (230, 230, 210))
    disk(d, 30, 160, 46, (255, 200, 60))  # the Sun at the left edge
    planets = [(70, 3, (170, 160, 150)), (95, 5, (230, 190, 120)), (122, 6, (80, 140, 230)),
               (150, 5, (200, 90, 60)), (195, 14, (215, 170, 120))]
    for k, (radius, size, rgb) in enumerate(planets):
        d.arc((30 - radius, 160 - radius * 1.3, 30 + radius, 160 + radius * 1.3), -70, 70,
              fill=(90, 100, 140), width=1)
        angle = math.radians(-50 + 25 * k)
        disk(d, 30 + radius * math.cos(angle), 160 + 1.3 * radius * math.sin(angle), size, rgb)
    return image


def moon_mars():
    image, d = canvas((16, 16, 28))
    # The Moon above, Mars below; a ball on each with an arrow as long as its weight.
    disk(d, 120, 150, 70, (165, 165, 170))  # the Moon
    disk(d, 95, 135, 10, (135, 135, 140))
    disk(d, 140, 165, 14, (135, 135, 140))
    disk(d, 120, 60, 14, (230, 230, 230))
    arrow_down(d, 120, 78, 12, (250, 210, 80))  # g(Moon) = 1.62 m/s^2
    disk(d, 120, 300, 55, (196, 92, 58))  # Mars
    disk(d, 100, 290, 9, (170, 76, 46))
    disk(d, 120, 218, 14, (230, 230, 230))
    arrow_down(d, 120, 234, 24, (250, 210, 80))  # g(Mars) = 3.71 m/s^2
    return image


def triceratops():
    image, d = canvas((222, 236, 200))
    d.rectangle((0, 250, W, H), fill=(150, 180, 110))
    body = (112, 150, 96)
    d.ellipse((60, 150, 200, 240), fill=body)                       # body
    d.polygon([(190, 180), (236, 205), (195, 215)], fill=body)     # tail
    for x in (80, 110, 160, 185):
        d.rectangle((x - 9, 225, x + 9, 262), fill=body)            # legs
    d.pieslice((8, 112, 98, 202), 180, 360, fill=(140, 170, 110))  # frill
    d.ellipse((20, 150, 82, 205), fill=body)                        # head
    d.polygon([(22, 178), (4, 188), (26, 192)], fill=(90, 120, 80))  # beak
    d.polygon([(30, 160), (18, 128), (40, 156)], fill=(240, 235, 210))  # nose horn
    for x in (48, 64):
        d.polygon([(x - 4, 154), (x - 20, 112), (x + 4, 150)], fill=(240, 235, 210))  # brow horns
    disk(d, 52, 168, 3, INK)
    return image


def dinosaur_touch():
    image, d = canvas((222, 236, 200))
    # The tail seen from the side, a fingertip pressing it: the skin dents under the finger.
    tail = [(0, 140), (240, 200), (240, 212), (0, 250)]
    d.polygon(tail, fill=(112, 150, 96))
    d.ellipse((96, 150, 146, 176), fill=(222, 236, 200))  # the dent
    d.ellipse((96, 116, 146, 166), fill=(236, 196, 170), outline=INK, width=2)  # fingertip
    d.rectangle((102, 20, 140, 142), fill=(236, 196, 170))
    d.line((102, 20, 102, 142), fill=INK, width=2)
    d.line((140, 20, 140, 142), fill=INK, width=2)
    arrow_down(d, 190, 80, 40, (200, 80, 60))
    return image


def daphnia():
    image, d = canvas((200, 228, 236))
    body = (170, 200, 190)
    d.ellipse((50, 90, 190, 250), fill=body, outline=(90, 120, 110), width=3)  # carapace
    d.ellipse((70, 60, 140, 120), fill=body, outline=(90, 120, 110), width=3)  # head
    disk(d, 92, 86, 9, INK)                                                     # eye
    d.line((175, 235, 220, 300), fill=(90, 120, 110), width=4)                  # tail spine
    for sign in (-1, 1):  # the branched swimming antennae
        x0, y0 = 78, 104
        x1, y1 = 30, 104 + sign * 30
        d.line((x0, y0, x1, y1), fill=(90, 120, 110), width=4)
        d.line((x1, y1, 8, y1 - 30), fill=(90, 120, 110), width=2)
        d.line((x1, y1, 10, y1 + 18), fill=(90, 120, 110), width=2)
    d.ellipse((110, 150, 160, 200), fill=(120, 160, 90))  # gut and brood
    return image


def microscope():
    image, d = canvas((236, 232, 220))
    # A magnifier over a drop of pond water, with the water flea inside it.
    disk(d, 110, 140, 90, (200, 228, 236), outline=INK, width=6)
    d.line((175, 205, 225, 290), fill=INK, width=14)
    d.ellipse((70, 110, 150, 190), fill=(170, 200, 190), outline=(90, 120, 110), width=3)
    disk(d, 88, 126, 6, INK)
    d.line((140, 182, 170, 215), fill=(90, 120, 110), width=3)  # the horn (tail spine)
    return image


IMAGES = {
    "solar_system": solar_system,
    "moon_mars": moon_mars,
    "triceratops": triceratops,
    "dinosaur_touch": dinosaur_touch,
    "daphnia": daphnia,
    "microscope": microscope,
}


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "images")
    os.makedirs(out, exist_ok=True)
    for name, draw in IMAGES.items():
        path = os.path.join(out, name + ".png")
        draw().save(path, optimize=True)
        print("wrote", os.path.normpath(path))


if __name__ == "__main__":
    main()
