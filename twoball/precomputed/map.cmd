twoball sweep twoball/precomputed/map.zarr --eps 0.5:1:21 --mu 1e-3:1:73:log --tau-ratio 1e-3:10:81:log --dtype float32
