twoball sweep twoball/precomputed/hertz-h1e2.zarr --eps 0.5:1:50 --mu 0.01:1/3:50 --tau-ratio 0.01:1:50 --height 1e2 --dtype float32 --force hertz
