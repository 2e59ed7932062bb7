"""Apollo (cyber RT) records ⇄ evoeye runs (docs/apollo.md). So far: the record container and
the message types, without Apollo or its pinned packages.

    protos  the vendored descriptors (schemas/external/apollo/apollo.desc) → message classes
    record  a cyber `.record` file read and written section by section
"""
