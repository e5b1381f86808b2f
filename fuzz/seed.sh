#!/usr/bin/env bash
# Builds the seed corpora of the fuzz targets in fuzz/corpus/<target>/ from the real recordings
# in ../shared/data (or $ODDBALL_DATA), the oddball-io test fixtures and a few small hand-made
# files. Only headers and the first records of the real files are taken, never whole files;
# corpus/ is not committed (.gitignore). Run from anywhere: `fuzz/seed.sh`.
#
# The `model` seeds are saved models of every pipeline preset, fitted on small synthetic data by
# the test `write_model_seeds` in crates/oddball-decode/tests/model_load.rs (a stable
# `cargo test`; set CARGO_TARGET_DIR to keep it away from a busy target dir, or SKIP_MODEL=1).
set -euo pipefail

fuzz="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$fuzz")"
data="${ODDBALL_DATA:-$root/../shared/data}"
fixtures="$root/crates/oddball-io/tests/fixtures"
corpus="$fuzz/corpus"

# ---------------------------------------------------------------- xdf
mkdir -p "$corpus/xdf" "$corpus/panel"
cp "$fixtures/xdf/python_small.xdf" "$corpus/xdf/"

# ---------------------------------------------------------------- fif
mkdir -p "$corpus/fif"
cp "$fixtures"/fif/*.fif "$corpus/fif/"

# ---------------------------------------------------------------- panel (WebSocket messages)
printf '{"t":"ping","id":3,"page_ms":12.5}' > "$corpus/panel/ping"
printf '{"t":"on","id":7,"code":2,"on_ms":1000.0}' > "$corpus/panel/on"
printf '{"t":"off","id":7,"off_ms":1100.2}' > "$corpus/panel/off"
printf '{"t":"hello","frame_ms":16.7,"agent":"HeadlessChrome"}' > "$corpus/panel/hello"

for t in bci2000 csv edf easy nic model xdf panel mat brainvision eeglab; do mkdir -p "$corpus/$t"; done

# ---------------------------------------------------------------- mat
# The MAT fixtures (v5, v7 compressed, narrow types, big-endian, BCI layout, v7.3 header) and the
# first 64 KiB of a real BCI Competition run (header and the first variables, cut mid-variable).
cp "$fixtures"/mat/*.mat "$corpus/mat/"
if [ -f "$data/bci-competition-ii-iib/AAS010R01.mat" ]; then
    head -c 65536 "$data/bci-competition-ii-iib/AAS010R01.mat" > "$corpus/mat/AAS010R01_head.mat"
fi

# ---------------------------------------------------------------- brainvision, eeglab
# Each BrainVision fixture as one input: u16 LE header length, u16 LE marker length, the
# header, the markers, the data. Each EEGLAB .set with its .fdt (or none) at the end, behind
# the .fdt's u16 LE length.
u16le() { printf '\\x%02x\\x%02x' $(($1 & 255)) $(($1 >> 8)); }
for stem in mne_float32 pybv_int16 hand_int32_vec; do
    b="$fixtures/brainvision/$stem"
    { printf "$(u16le "$(wc -c < "$b.vhdr")")$(u16le "$(wc -c < "$b.vmrk")")"
      cat "$b.vhdr" "$b.vmrk" "$b.eeg"; } > "$corpus/brainvision/$stem"
done
for set in mne_export struct_fdt epoched; do
    fdt="$fixtures/eeglab/$set.fdt"
    n=0; [ -f "$fdt" ] && n=$(wc -c < "$fdt")
    { printf "$(u16le "$n")"; cat "$fixtures/eeglab/$set.set"
      if [ -f "$fdt" ]; then cat "$fdt"; fi; } > "$corpus/eeglab/$set"
done

# ---------------------------------------------------------------- bci2000
# A BCI2000 v1.1 file: 2 channels of `fmt` (each sample the bytes `sample`, printf escapes),
# 3 states in 1 state byte, 24 samples.
small_bci2000() {
    local fmt=$1 sample=$2 rest first n prev
    rest=$'[ State Vector Definition ]\r\nStimulusCode 5 0 0 0\r\nStimulusType 1 0 0 5\r\nPhaseInSequence 2 0 0 6\r\n'
    rest+=$'[ Parameter Definition ]\r\nSource int SamplingRate= 100Hz 256Hz 1 % // rate\r\n'
    rest+=$'Source list ChannelNames= 2 Cz Pz // names\r\nSource floatlist SourceChGain= 2 0.1 0.2muV 0 % % // gain\r\n'
    rest+=$'Source floatlist SourceChOffset= 1 3 // offset\r\n'
    rest+=$'App matrix TargetDefinitions= 4 { Display Enter } A A B B C C D D // t\r\n'
    rest+=$'App intlist NumMatrixRows= 1 2 // r\r\nApp intlist NumMatrixColumns= 1 2 // c\r\n'
    rest+=$'App int NumberOfSequences= 2 // n\r\nApp string TextToSpell= AD // t\r\n'
    rest+=$'App matrix M= { a b } { c } %20 { x { y } } // nested\r\n\r\n'
    n=0 prev=-1
    while [ "$n" != "$prev" ]; do
        prev=$n
        first="BCI2000V= 1.1 HeaderLen= $n SourceCh= 2 StatevectorLen= 1 DataFormat= $fmt"$'\r\n'
        n=$(( ${#first} + ${#rest} ))
    done
    printf '%s%s' "$first" "$rest"
    # 24 records of 2 samples and 1 state byte (code in bits 0-4, type in bit 5, phase 6-7).
    local t code
    for t in $(seq 0 23); do
        code=0
        if [ $((t % 4)) = 1 ]; then code=$(( (t / 4) % 4 + 1 )); fi
        printf "$sample$sample"
        printf "\\$(printf '%03o' $(( code | (code == 1) << 5 | 2 << 6 )))"
    done
}
small_bci2000 int16 '\x05\xff' > "$corpus/bci2000/small_int16.dat"
small_bci2000 int32 '\x05\x00\x01\x00' > "$corpus/bci2000/small_int32.dat"
small_bci2000 float32 '\x00\x00\x80\x3f' > "$corpus/bci2000/small_float32.dat"

for f in "$data"/bci2000-samplefiles-p300/*.dat; do
    [ -f "$f" ] || continue
    name=$(basename "$f" .dat)
    # The first line: HeaderLen= N SourceCh= C StatevectorLen= S (v1.0: int16 samples).
    read -r _ hlen _ nch _ svlen < <(head -n 1 "$f" | tr -d '\r')
    rec=$(( nch * 2 + svlen ))
    # The whole header and the first 16 sample records: a valid small file.
    head -c $(( hlen + 16 * rec )) "$f" > "$corpus/bci2000/${name}_head16.dat"
    # The first 4 kB: a truncated header.
    head -c 4096 "$f" > "$corpus/bci2000/${name}_4k.dat"
done

# ---------------------------------------------------------------- csv
i=0
for f in "$data"/muse-visual-p300-eeg-notebooks/subject1/session*/*.csv; do
    [ -f "$f" ] || continue
    i=$((i + 1))
    [ $i -le 3 ] || break
    head -n 40 "$f" > "$corpus/csv/muse_$i.csv"
done
printf 'time,Cz,Pz,stim\n0.000,1.5,-2,0\n0.004,1e1,3.25,1\n0.008,0,0,1\n0.012,-4,5,0\n0.016,2,2,2\n' \
    > "$corpus/csv/generic.csv"
printf '\xef\xbb\xbf"timestamps","TP9","AF7","AF8","TP10","Right AUX","Marker0"\r\n1.0,1,2,3,4,5,0\r\n1.004,1,2,3,4,5,2\r\n1.008,1,2,3,4,5,1\r\n' \
    > "$corpus/csv/muse_bom_crlf.csv"
printf 'a;b;c\n1;2;3\n4;5;6\n' > "$corpus/csv/semicolon.csv"

# ---------------------------------------------------------------- edf
cp "$fixtures/pyedflib_small.edf" "$corpus/edf/"
cp "$fixtures/numpy_small.bdf" "$corpus/edf/"
for f in "$fixtures/pyedflib_small.edf" "$fixtures/numpy_small.bdf"; do
    # The header alone (256 + 256 × ns bytes, ns at byte 252).
    ns=$(dd if="$f" bs=1 skip=252 count=4 2>/dev/null | tr -d ' ')
    head -c $(( 256 + 256 * ns )) "$f" > "$corpus/edf/$(basename "$f").header"
done

# ---------------------------------------------------------------- easy
sep=$'\x00INFO\x00'
{ cat "$fixtures/nic_small.easy"; printf '%s' "$sep"; cat "$fixtures/nic_small.info"; } \
    > "$corpus/easy/nic_small_with_info"
cp "$fixtures/nic_small.easy" "$corpus/easy/nic_small"
cp "$fixtures/nic_small_noinfo.easy" "$corpus/easy/nic_small_noinfo"
{ head -n 8 "$fixtures/nic_small.easy"; printf '%s' "$sep"; head -n 14 "$fixtures/nic_small.info"; } \
    > "$corpus/easy/nic_head8_with_info"

# ---------------------------------------------------------------- nic
# Header: flags (bit 0 ASCII, bit 1 trigger, bit 2 timestamp), channel count, piece-size seed.
# ASCII frames: 8 channels, trigger, timestamp from the .easy fixture's columns 1-8, 12, 13.
{
    printf '\x07\x08\x2a'
    awk -F'\t' 'NR <= 12 {
        body = $1; for (k = 2; k <= 8; k++) body = body "\t" $k
        body = body "\t" $12 "\t" $13; sub(/\r$/, "", body)
        printf "%05d\t%s", length(body), body
    }' "$fixtures/nic_small.easy"
} > "$corpus/nic/ascii_starstim8"
{ printf '\x01\x02\x05'; printf '00003\t1\t200004\t-5\t7'; } > "$corpus/nic/ascii_2ch"
# Binary frames are any bytes: take some from a real recording's body.
dat=$(ls "$data"/bci2000-samplefiles-p300/*.dat 2>/dev/null | head -n 1 || true)
if [ -n "$dat" ]; then
    { printf '\x06\x08\x11'; tail -c 2048 "$dat"; } > "$corpus/nic/binary_starstim8"
    { printf '\x00\x04\x03'; tail -c 512 "$dat"; } > "$corpus/nic/binary_4ch"
else
    { printf '\x06\x08\x11'; head -c 2048 "$fixtures/numpy_small.bdf"; } > "$corpus/nic/binary_starstim8"
fi

# ---------------------------------------------------------------- gdf
# The GDF fixtures (1.25 with OpenViBE codes, 2.20 with a mode-3 table, every data type) and the
# header and first 256 records of the real OpenViBE file (cut before its event table).
mkdir -p "$corpus/gdf"
cp "$fixtures"/gdf/*.gdf "$fixtures"/gdf/types/*.gdf "$corpus/gdf/"
if [ -f "$data/openvibe-p300-gdf/data_sample_8ch.gdf" ]; then
    head -c $(( 2304 + 256 * 64 )) "$data/openvibe-p300-gdf/data_sample_8ch.gdf" > "$corpus/gdf/openvibe_head.gdf"
fi

# ---------------------------------------------------------------- model
if [ "${SKIP_MODEL:-0}" != 1 ]; then
    ODDBALL_MODEL_SEED_DIR="$corpus/model" \
        cargo test --manifest-path "$root/Cargo.toml" -p oddball-decode --test model_load \
        -- --exact write_model_seeds --nocapture
fi

for t in bci2000 csv edf easy nic model xdf panel mat brainvision eeglab; do
    printf '%-8s %3d seeds\n' "$t" "$(ls "$corpus/$t" | wc -l)"
done
