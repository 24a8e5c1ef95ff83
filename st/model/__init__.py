"""The compiled-program model: what the compiler produces and the runtime, the test runner and the
I/O layers read. A leaf package: it imports only the standard library, st.source and
st.diagnostics, so the runtime can load a compiled program without importing the compiler.

    types.py      the IEC type model (elementary types, arrays, structs, POUs, variables)
    program.py    the checked program: configurations, tasks, instances, SFC, tests
    summaries.py  AST-free stand-ins for what the compiler keeps as syntax (PouInfo, InitialValue, …)
    compiled.py   CompiledProgram: code objects + the model, with a versioned serialisation
    addresses.py  direct addresses and the process image's geometry
    literals.py   literal text ↔ values (times and dates as nanoseconds)
"""
