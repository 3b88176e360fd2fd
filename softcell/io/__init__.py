"""Everything that touches a file or a screen: NetCDF, video, figures, reports."""
