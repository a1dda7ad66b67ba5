# Glimpse: glimpse-server (gRPC :50051, Prometheus metrics :9464) and the glimpse client, on Debian 12.
#   podman build --format docker -t glimpse:dev .     (docker build -t glimpse:dev . with a Docker engine)
#   podman run -p 50051:50051 -p 9464:9464 -v glimpse-db:/var/lib/glimpse glimpse:dev
# deploy/README.md has the rest; deploy/container-smoke.sh builds, runs and checks this image.

# ---- build: the compilers and -dev packages, then the two executables --------------------------
FROM debian:bookworm AS build
COPY deploy/install-deps.sh /src/deploy/install-deps.sh
# Its own layer, so a source change rebuilds only what follows.
RUN bash /src/deploy/install-deps.sh && rm -rf /var/lib/apt/lists/*
COPY CMakeLists.txt /src/
COPY core /src/core
COPY proto /src/proto
COPY server /src/server
COPY client /src/client
RUN cmake -S /src -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release \
          -DGLIMPSE_BUILD_TESTS=OFF -DGLIMPSE_BUILD_BENCH=OFF \
 && cmake --build /build --target glimpse-server glimpse -j "$(nproc)"
# Just the two executables (cmake --install would also want glimpse-lab, which is not built here).
RUN install -D -s -m 0755 -t /opt/glimpse/bin /build/server/glimpse-server /build/client/glimpse

# ---- runtime: shared libraries only, a non-root user, the model store on a volume --------------
FROM debian:bookworm
LABEL org.opencontainers.image.title="glimpse" \
      org.opencontainers.image.description="Recognise an object's category from a partial point cloud (gRPC service)" \
      org.opencontainers.image.source="deploy/README.md"
COPY deploy/install-deps.sh /tmp/install-deps.sh
RUN bash /tmp/install-deps.sh --runtime && rm -rf /var/lib/apt/lists/* /tmp/install-deps.sh \
 && useradd --system --uid 10001 --user-group --home-dir /var/lib/glimpse --shell /usr/sbin/nologin glimpse \
 && mkdir -p /var/lib/glimpse && chown glimpse:glimpse /var/lib/glimpse
COPY --from=build /opt/glimpse/bin/glimpse-server /opt/glimpse/bin/glimpse /usr/local/bin/
COPY deploy/model-sync.sh /usr/local/bin/glimpse-model-sync

# The server reads GLIMPSE_* variables (glimpse-server --help); the client's GLIMPSE_SERVER is what
# the health check below (and `podman exec ... glimpse`) talks to.
ENV GLIMPSE_DB=/var/lib/glimpse/glimpse.db \
    GLIMPSE_ADDRESS=0.0.0.0:50051 \
    GLIMPSE_METRICS_PORT=9464 \
    GLIMPSE_SERVER=localhost:50051
VOLUME ["/var/lib/glimpse"]
WORKDIR /var/lib/glimpse
USER glimpse
EXPOSE 50051 9464
# No --start-period: the server answers within a second of starting (and dockerfilelint 1.8 reads
# "--start-period" as the unknown option "--start").
HEALTHCHECK --interval=30s --timeout=5s --retries=3 \
  CMD ["glimpse", "health", "--timeout", "3"]
ENTRYPOINT ["glimpse-server"]
