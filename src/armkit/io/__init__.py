"""Every file format armkit reads or writes, in one place, with the same precise errors.

`armkit.io.documents` holds the YAML and text helpers that every reader uses.
"""
