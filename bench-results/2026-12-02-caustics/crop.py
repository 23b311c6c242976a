import sys, subprocess, zlib, struct
def read(path):
    d = subprocess.run(['convert', path, 'ppm:-'], capture_output=True).stdout
    parts = []; i = 0
    while len(parts) < 4:
        while d[i:i+1].isspace(): i += 1
        if d[i:i+1] == b'#':
            while d[i:i+1] != b'\n': i += 1
            continue
        j = i
        while not d[j:j+1].isspace(): j += 1
        parts.append(d[i:j]); i = j
    i += 1
    w, h = int(parts[1]), int(parts[2])
    return w, h, d[i:i+w*h*3]
def crop(img, x0, y0, cw, ch, s):
    w, h, px = img
    rows = []
    for y in range(ch):
        row = bytearray()
        for x in range(cw):
            o = ((y0+y)*w + x0+x)*3
            row += px[o:o+3]*s
        for _ in range(s): rows.append(bytes(row))
    return rows
def write(path, rows):
    h = len(rows); w = len(rows[0])//3
    raw = b''.join(b'\x00'+r for r in rows)
    def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t+d) & 0xffffffff)
    open(path, 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
out = sys.argv[1]; x0, y0, cw, ch, s = map(int, sys.argv[2:7]); files = sys.argv[7:]
crops = [crop(read(f), x0, y0, cw, ch, s) for f in files]
rows = [b''.join(c[i] + b'\x80\x80\x80'*2 for c in crops) for i in range(len(crops[0]))]
write(out, rows)
