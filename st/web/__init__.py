"""The online mode in the browser (`st run --web`): watch, write and force a running PLC, see its
tasks, faults, axes, EtherCAT slaves and Modbus clients (docs/web.md).

link.py (in the PLC process, between two jobs) ⇄ channel.py (shared memory) ⇄ server.py (its
own process: Starlette on uvicorn, one WebSocket per page) → static/ (the page, no build step).
"""
