# voxd container: built with the same scripts CI runs (scripts/install-deps.sh,
# scripts/build.sh), so a green CI proves these steps.
#   docker build -t voxd .
#   docker run -p 8080:8080 -v voxd-data:/var/lib/voxd voxd

FROM debian:12 AS build
WORKDIR /src
COPY . .
RUN ./scripts/install-deps.sh && BUILD_DIR=build ./scripts/build.sh

FROM debian:12-slim
# Only the shared libraries the binary links (checked against ldd by a test).
COPY scripts/install-deps.sh /usr/local/lib/voxd/install-deps.sh
RUN /usr/local/lib/voxd/install-deps.sh --runtime && rm -rf /var/lib/apt/lists/*
RUN useradd --system --uid 10001 --user-group --home-dir /var/lib/voxd --create-home voxd
COPY --from=build /src/build/server/voxd /usr/local/bin/voxd
USER 10001:10001
ENV VOXD_HOST=0.0.0.0 \
    VOXD_PORT=8080 \
    VOXD_DATA_DIR=/var/lib/voxd
VOLUME /var/lib/voxd
EXPOSE 8080
HEALTHCHECK --interval=10s --timeout=3s --start-period=10s --retries=3 \
  CMD curl -fsS http://127.0.0.1:8080/healthz || exit 1
STOPSIGNAL SIGTERM
ENTRYPOINT ["/usr/local/bin/voxd"]
CMD ["serve"]
