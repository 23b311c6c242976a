#!/bin/sh
./after.sh "" demo /work/refs-stbpt/ref-demo-64
./after.sh /work/shared/peers/cornell-moving.glb cm /work/refs-stbpt/ref-cm-64b
