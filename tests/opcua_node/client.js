#!/usr/bin/env node
// An independent OPC UA client (node-opcua) against st's OPC UA server (tests/test_opcua_node.py).
//
//   node client.js ENDPOINT USER PASSWORD SERVER_PKI CLIENT_PKI [--expect-untrusted]
//
// ENDPOINT: opc.tcp://host:port/st/; SERVER_PKI: the st server's PKI folder (its certificate,
// own/cert.der, is trusted by this client); CLIENT_PKI: this client's own PKI folder (its
// certificate is made there on the first run and reused after). The connection is always
// SignAndEncrypt + Basic256Sha256 with a user name and password.
//
// With --expect-untrusted the client only tries to connect and expects the server to refuse
// its certificate with BadCertificateUntrusted (exit 0 when so refused, 3 when it got in). Otherwise it browses Objects →
// Programs → main, reads, subscribes for 1.5 s, writes, and prints one JSON object on stdout.
// Exit codes: 0 done (the JSON says what happened), 2 an unexpected error (JSON with "error").
"use strict";

// node-opcua's loggers write to stdout (console.log): keep stdout for the one JSON object.
const out = process.stdout.write.bind(process.stdout);
console.log = (...a) => console.error(...a);
console.info = (...a) => console.error(...a);
console.warn = (...a) => console.error(...a);

const fs = require("node:fs");
const path = require("node:path");
const {
    OPCUAClient,
    OPCUACertificateManager,
    MessageSecurityMode,
    SecurityPolicy,
    UserTokenType,
    AttributeIds,
    DataType,
    StatusCodes,
    TimestampsToReturn,
    ClientMonitoredItem,
} = require("node-opcua");

const [endpoint, user, password, serverPki, clientPki, flag] = process.argv.slice(2);
const EXPECT_UNTRUSTED = flag === "--expect-untrusted";
const SUBSCRIBE_MS = 1500;

function emit(obj, code) {
    out(JSON.stringify(obj) + "\n", () => process.exit(code));
}

function sleep(ms) {
    return new Promise((resolve) => setTimeout(resolve, ms));
}

function plain(value) {
    if (typeof value === "bigint") return value.toString();
    if (Array.isArray(value) || ArrayBuffer.isView(value)) return Array.from(value, plain);
    if (value && typeof value === "object" && typeof value.toJSON === "function") return value.toJSON();
    return value;
}

function dataValue(dv) {
    return {
        status: dv.statusCode.name,
        value: dv.value ? plain(dv.value.value) : null,
        dataType: dv.value ? DataType[dv.value.dataType] : null,
        sourceTimestamp: dv.sourceTimestamp ? dv.sourceTimestamp.toISOString() : null,
    };
}

async function main() {
    if (!endpoint || !user || !password || !serverPki || !clientPki) {
        throw new Error("usage: node client.js ENDPOINT USER PASSWORD SERVER_PKI CLIENT_PKI [--expect-untrusted]");
    }
    const result = { endpoint, node_opcua: require("node-opcua/package.json").version, node: process.version };

    const certificateManager = new OPCUACertificateManager({
        rootFolder: clientPki,
        automaticallyAcceptUnknownCertificate: false,
    });
    await certificateManager.initialize();
    // trust the st server's own certificate (nothing else)
    const serverCert = fs.readFileSync(path.join(serverPki, "own", "cert.der"));
    await certificateManager.trustCertificate(serverCert);

    const client = OPCUAClient.create({
        applicationName: "st-node-opcua-test",
        applicationUri: "urn:st:test:node-opcua-client",
        clientCertificateManager: certificateManager,
        securityMode: MessageSecurityMode.SignAndEncrypt,
        securityPolicy: SecurityPolicy.Basic256Sha256,
        endpointMustExist: false,
        keepSessionAlive: false,
        requestedSessionTimeout: 20000,
        connectionStrategy: { maxRetry: 0, initialDelay: 100, maxDelay: 200 },
    });
    let connectError = null;
    client.on("connection_failed", (err) => {
        connectError = connectError || err;
    });
    try {
        await client.connect(endpoint);
    } catch (err) {
        result.connected = false;
        result.error = String((connectError && connectError.message) || err.message || err);
        result.client_certificate = client.certificateFile;
        return [result, EXPECT_UNTRUSTED && /BadCertificateUntrusted/.test(result.error) ? 0 : 2];
    }
    result.connected = true;
    result.client_certificate = client.certificateFile;
    if (EXPECT_UNTRUSTED) {
        // the secure channel opened: the server may still refuse the certificate at CreateSession
        let code = 3; // got in: not what was expected
        try {
            const s = await client.createSession({ type: UserTokenType.UserName, userName: user, password });
            await s.close();
            result.session = true;
        } catch (err) {
            result.session = false;
            result.error = String(err.message || err);
            code = /BadCertificateUntrusted/.test(result.error) ? 0 : 2;
        }
        await client.disconnect();
        return [result, code];
    }

    const session = await client.createSession({ type: UserTokenType.UserName, userName: user, password });
    try {
        result.security = {
            mode: MessageSecurityMode[client.securityMode],
            policy: client.securityPolicy,
        };
        const namespaces = await session.readNamespaceArray();
        const ns = namespaces.indexOf("urn:st:st");
        result.namespace_index = ns;
        const id = (p) => `ns=${ns};s=${p}`;

        // ---- browse Objects → Programs → main
        const names = async (nodeId) => {
            const br = await session.browse(nodeId);
            if (br.statusCode !== StatusCodes.Good) throw new Error(`browse ${nodeId}: ${br.statusCode.name}`);
            return br.references.map((r) => ({ name: r.browseName.name, nodeId: r.nodeId.toString() }));
        };
        const objects = await names("i=85");
        result.objects = objects.map((r) => r.name);
        const programs = objects.find((r) => r.name === "Programs");
        if (!programs) throw new Error("no Programs under Objects");
        const instances = await names(programs.nodeId);
        result.programs = instances.map((r) => r.name);
        const mainRef = instances.find((r) => r.name === "main");
        if (!mainRef) throw new Error("no main under Programs");
        result.main_node = mainRef.nodeId;
        result.browse = (await names(mainRef.nodeId)).map((r) => r.name);

        // ---- read
        const paths = ["main.setpoint", "main.counter", "main.level"];
        const read = await session.read(paths.map((p) => ({ nodeId: id(p), attributeId: AttributeIds.Value })));
        result.read = Object.fromEntries(paths.map((p, k) => [p, dataValue(read[k])]));
        const access = await session.read(
            paths.map((p) => ({ nodeId: id(p), attributeId: AttributeIds.UserAccessLevel })),
        );
        result.user_access_level = Object.fromEntries(paths.map((p, k) => [p, plain(access[k].value.value)]));

        // ---- subscribe: data change notifications of main.counter for SUBSCRIBE_MS
        const subscription = await session.createSubscription2({
            requestedPublishingInterval: 100,
            requestedLifetimeCount: 100,
            requestedMaxKeepAliveCount: 10,
            maxNotificationsPerPublish: 100,
            publishingEnabled: true,
            priority: 10,
        });
        const counts = {};
        const lastValues = {};
        const items = [];
        for (const p of ["main.counter", "main.level"]) {
            counts[p] = 0;
            const item = ClientMonitoredItem.create(
                subscription,
                { nodeId: id(p), attributeId: AttributeIds.Value },
                { samplingInterval: 100, discardOldest: true, queueSize: 10 },
                TimestampsToReturn.Both,
            );
            item.on("changed", (dv) => {
                counts[p] += 1;
                lastValues[p] = plain(dv.value.value);
            });
            items.push(item);
        }
        await sleep(SUBSCRIBE_MS);
        result.subscription = {
            revised_publishing_interval: subscription.publishingInterval,
            window_ms: SUBSCRIBE_MS,
            notifications: counts,
            last_values: lastValues,
        };
        await subscription.terminate();

        // ---- write: right type, wrong type, read-only
        const write = async (p, dataType, value) => {
            const [sc] = await session.write([
                { nodeId: id(p), attributeId: AttributeIds.Value, value: { value: { dataType, value } } },
            ]);
            return sc.name;
        };
        result.write = {
            setpoint_int16: await write("main.setpoint", DataType.Int16, 42),
            setpoint_int32: await write("main.setpoint", DataType.Int32, 43),
            counter_int32: await write("main.counter", DataType.Int32, 7),
        };
        // read the written value back (it reaches the node with the next snapshot)
        let back = null;
        for (let k = 0; k < 40; k++) {
            const [dv] = await session.read([{ nodeId: id("main.setpoint"), attributeId: AttributeIds.Value }]);
            back = dataValue(dv);
            if (back.value === 42) break;
            await sleep(50);
        }
        result.read_back = back;
    } finally {
        await session.close();
        await client.disconnect();
    }
    return [result, 0];
}

main().then(
    ([result, code]) => emit(result, code),
    (err) => emit({ error: String((err && err.stack) || err) }, 2),
);
