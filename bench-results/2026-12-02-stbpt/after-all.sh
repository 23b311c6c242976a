#!/bin/sh
./after.sh builtin:dolly dolly /work/refs/ref-dolly-64
./after.sh /work/shared/scenes/RiggedSimple.glb rigged /work/refs-stbpt/ref-rigged-64b --stage cornell
