"""Apollo (cyber RT) records ⇄ evoeye runs, without Apollo or its pinned packages (docs/apollo.md).

    protos   Apollo's message classes from vendored descriptors (schemas/external/apollo)
    record   a cyber `.record` file read and written section by section
    convert  one Apollo message → evoeye's conventions (as the Autoware converters give them)
    run      a record → an evoeye run, through Autoware's frame assembler and import contract
    export   an evoeye run log → a record
"""
