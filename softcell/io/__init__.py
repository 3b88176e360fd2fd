"""Files: NetCDF with checksums, atomic writes and the rules every output follows, the
compiled-model cache on disk, configuration files, exports (GSD, movement) and the pages
softcell writes for people."""
